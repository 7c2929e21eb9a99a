// A race TSan must report under the options scripts/sanitize.sh --thread runs the tests with:
// two threads write one int, one of them from a callback a library thread would call. If this
// exits 0, the options (ignore_noninstrumented_modules, the suppressions) have made TSan blind
// to our code and the suite's silence means nothing.
#include <functional>
#include <thread>

int shared_value = 0;

int main() {
  std::function<void()> callback = [] { shared_value = 1; };
  std::thread worker(callback);
  shared_value = 2;
  worker.join();
  return shared_value == 0 ? 1 : 0;
}
