// Test helper for security_dds_test: a listener in its own process (as on another host), so
// no vendor can hand samples over inside one process around the security plugins.
//   security_listener <vendor> <domain> <topic> <keystore|-> <identity|->
// Prints "ready" once its reader exists; on SIGUSR1 prints "received <n> matched <m>", on
// SIGTERM prints the same and exits 0. A participant that cannot be created prints
// "error <why>" and exits 1.
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>

#include "auv/interfaces/backend.h"
#include "auv/msg/type_support.h"

namespace {
volatile sig_atomic_t g_stop = 0;
volatile sig_atomic_t g_report = 0;
void onSignal(int signal) { (signal == SIGTERM ? g_stop : g_report) = 1; }
}  // namespace

int main(int argc, char** argv) {
  using namespace auv::interfaces;
  if (argc != 6) {
    std::fprintf(stderr, "usage: %s <vendor> <domain> <topic> <keystore|-> <identity|->\n",
                 argv[0]);
    return 2;
  }
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGUSR1, &action, nullptr);
  const std::string keystore = argv[4], identity = argv[5];
  ParticipantOptions options(std::atoi(argv[2]), "listener");
  options.security = SecurityIdentity{keystore == "-" ? "" : keystore, identity, true};
  const auv::msg::TypeSupport* type = auv::msg::findType("auv::msg::String");
  std::atomic<int> received{0};
  try {
    auto participant = createParticipant(vendorFromString(argv[1]), options);
    QosProfile qos;
    qos.reliability = Reliability::RELIABLE;
    qos.history = History::KEEP_LAST;
    qos.depth = 100;
    std::shared_ptr<void> sample = type->create_sample();
    std::mutex mutex;
    const auto drain = [&](DataReader& r) {
      std::lock_guard<std::mutex> lock(mutex);
      while (r.take(sample.get(), nullptr)) ++received;
    };
    auto reader = participant->createReader(argv[3], *type, qos, drain);
    std::printf("ready\n");
    std::fflush(stdout);
    for (bool last = false; !last;) {
      ::usleep(2000);
      last = g_stop;
      if (!last && !g_report) continue;
      g_report = 0;
      // Take here too: a sample already acknowledged may not have reached the callback yet.
      drain(*reader);
      std::printf("received %d matched %d\n", received.load(), reader->matchedWriters());
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::printf("error %s\n", e.what());
    std::fflush(stdout);
    return 1;
  }
  return 0;
}
