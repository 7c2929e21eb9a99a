// ThreadSanitizer in clang 14 (Debian 12) has no interceptors for glibc's pthread_mutex_clocklock
// and pthread_rwlock_clock{rd,wr}lock (llvm/llvm-project#62623). libstdc++'s timed mutexes call
// them (std::timed_mutex::try_lock_until on steady_clock), and so does Fast DDS: TSan then sees
// the unlock but not the lock, reports "unlock of an unlocked mutex" and loses every
// happens-before edge those mutexes make, which turns into false races in our callbacks. This
// library, preloaded into the TSan test runs only (scripts/sanitize.sh --thread), forwards the
// three calls to their CLOCK_REALTIME twins, which TSan does intercept.
#define _GNU_SOURCE
#include <pthread.h>
#include <time.h>

static struct timespec realtimeDeadline(clockid_t clock, const struct timespec* deadline) {
  if (clock == CLOCK_REALTIME) return *deadline;
  struct timespec now_clock, now_real;
  clock_gettime(clock, &now_clock);
  clock_gettime(CLOCK_REALTIME, &now_real);
  long long remaining_ns = (long long)(deadline->tv_sec - now_clock.tv_sec) * 1000000000LL +
                           (deadline->tv_nsec - now_clock.tv_nsec);
  if (remaining_ns < 0) remaining_ns = 0;
  long long total_ns = (long long)now_real.tv_nsec + remaining_ns % 1000000000LL;
  struct timespec real;
  real.tv_sec =
      now_real.tv_sec + (time_t)(remaining_ns / 1000000000LL) + (time_t)(total_ns / 1000000000LL);
  real.tv_nsec = (long)(total_ns % 1000000000LL);
  return real;
}

int pthread_mutex_clocklock(pthread_mutex_t* mutex, clockid_t clock,
                            const struct timespec* deadline) {
  const struct timespec real = realtimeDeadline(clock, deadline);
  return pthread_mutex_timedlock(mutex, &real);
}

int pthread_rwlock_clockrdlock(pthread_rwlock_t* lock, clockid_t clock,
                               const struct timespec* deadline) {
  const struct timespec real = realtimeDeadline(clock, deadline);
  return pthread_rwlock_timedrdlock(lock, &real);
}

int pthread_rwlock_clockwrlock(pthread_rwlock_t* lock, clockid_t clock,
                               const struct timespec* deadline) {
  const struct timespec real = realtimeDeadline(clock, deadline);
  return pthread_rwlock_timedwrlock(lock, &real);
}
