// auv_link_impair: a user-space link impairer for kernels without netem (README.md). It binds an
// NFQUEUE queue (libnetfilter_queue), and for each packet an iptables rule hands it drops it or
// holds it and accepts it later (the decisions: link_impair.h). It sets up no iptables rule:
// the caller adds one with --queue-bypass, so the link passes everything while the tool is not
// running.
//
// Exit status: 0 after SIGINT/SIGTERM, 1 on a runtime error, 2 for bad options, 3 when the
// queue cannot be bound (no CAP_NET_ADMIN, no nfnetlink_queue in the kernel, queue in use).
#include <arpa/inet.h>
#include <linux/netfilter.h>  // NF_ACCEPT, NF_DROP
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <libnetfilter_queue/libnetfilter_queue.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "link_impair.h"

namespace {

using auv::link_impair::Decision;
using auv::link_impair::Impairer;
using auv::link_impair::Options;
using auv::link_impair::Verdict;

volatile sig_atomic_t g_signal = 0;

void onSignal(int signal) { g_signal = signal; }

int64_t nowUs() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000 + t.tv_nsec / 1000;
}

struct Context {
  Impairer* impairer = nullptr;
  nfq_q_handle* queue = nullptr;
  bool draining = false;  // shutting down: accept everything at once
  uint64_t verdict_errors = 0;
  // How late held packets were accepted after their time (scheduling of this process).
  int64_t late_max_us = 0;
  int64_t late_sum_us = 0;
  uint64_t late_count = 0;
  std::vector<uint32_t> ids;     // scratch
  std::vector<int64_t> release;  // scratch
};

void issue(Context* context, uint32_t id, uint32_t verdict) {
  if (nfq_set_verdict(context->queue, id, verdict, 0, nullptr) < 0) {
    if (context->verdict_errors++ == 0) {
      std::fprintf(stderr, "link_impair: verdict for packet %u failed: %s\n", id,
                   std::strerror(errno));
    }
  }
}

void releaseDue(Context* context, int64_t now_us) {
  context->ids.clear();
  context->release.clear();
  context->impairer->takeDue(now_us, &context->ids, &context->release);
  for (uint32_t id : context->ids) issue(context, id, NF_ACCEPT);
  for (int64_t release : context->release) {
    context->late_max_us = std::max(context->late_max_us, now_us - release);
    context->late_sum_us += now_us - release;
  }
  context->late_count += context->release.size();
}

int onPacket(nfq_q_handle*, nfgenmsg*, nfq_data* data, void* opaque) {
  auto* context = static_cast<Context*>(opaque);
  const nfqnl_msg_packet_hdr* header = nfq_get_msg_packet_hdr(data);
  if (header == nullptr) return 0;
  const uint32_t id = ntohl(header->packet_id);
  if (context->draining) {
    issue(context, id, NF_ACCEPT);
    return 0;
  }
  const int64_t now = nowUs();
  releaseDue(context, now);  // those due before this one arrived go first
  const Decision decision = context->impairer->arrive(id, now);
  if (decision.verdict == Verdict::kDrop) issue(context, id, NF_DROP);
  if (decision.verdict == Verdict::kAccept) issue(context, id, NF_ACCEPT);
  return 0;  // kHold: its verdict comes from releaseDue
}

void printCounters(const char* when, const Context& context, uint64_t netlink_lost) {
  const double late_mean_ms =
      context.late_count > 0 ? context.late_sum_us / 1000.0 / context.late_count : 0.0;
  std::printf(
      "link_impair: %s: %s netlink_lost %llu verdict_errors %llu late_ms mean %.3f max %.3f\n",
      when,
      auv::link_impair::formatCounters(context.impairer->counters(), context.impairer->held())
          .c_str(),
      static_cast<unsigned long long>(netlink_lost),
      static_cast<unsigned long long>(context.verdict_errors), late_mean_ms,
      context.late_max_us / 1000.0);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Options options;
  const std::string error =
      auv::link_impair::parseOptions(std::vector<std::string>(argv + 1, argv + argc), &options);
  if (options.help) {
    std::fputs(auv::link_impair::usage().c_str(), stdout);
    return 0;
  }
  if (!error.empty()) {
    std::fprintf(stderr, "auv_link_impair: %s\n", error.c_str());
    return 2;
  }
  if (!options.seed_given) options.seed = std::random_device{}();

  // SIGINT/SIGTERM are blocked except inside ppoll, so a signal never slips in between the
  // check of g_signal and the wait.
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigset_t blocked, during_wait;
  sigemptyset(&blocked);
  sigaddset(&blocked, SIGINT);
  sigaddset(&blocked, SIGTERM);
  sigprocmask(SIG_BLOCK, &blocked, &during_wait);
  sigdelset(&during_wait, SIGINT);
  sigdelset(&during_wait, SIGTERM);

  nfq_handle* handle = nfq_open();
  if (handle == nullptr) {
    std::fprintf(stderr, "auv_link_impair: cannot open a netfilter queue handle: %s\n",
                 std::strerror(errno));
    return 3;
  }
  Impairer impairer(options);
  Context context;
  context.impairer = &impairer;
  context.queue =
      nfq_create_queue(handle, static_cast<uint16_t>(options.queue), onPacket, &context);
  if (context.queue == nullptr) {
    std::fprintf(stderr,
                 "auv_link_impair: --queue %d: cannot bind: %s (needs CAP_NET_ADMIN in the "
                 "namespace, nfnetlink_queue in the kernel, and no other program on the queue)\n",
                 options.queue, std::strerror(errno));
    nfq_close(handle);
    return 3;
  }
  // Only the metadata (the packet id): the decision does not look inside. The kernel queue
  // takes the held packets and a margin; with FAIL_OPEN a full kernel queue passes packets
  // instead of dropping them.
  const uint32_t kernel_queue = static_cast<uint32_t>(options.capacity) + 1024;
  if (nfq_set_mode(context.queue, NFQNL_COPY_META, 0) < 0 ||
      nfq_set_queue_maxlen(context.queue, kernel_queue) < 0) {
    std::fprintf(stderr, "auv_link_impair: --queue %d: cannot configure: %s\n", options.queue,
                 std::strerror(errno));
    nfq_destroy_queue(context.queue);
    nfq_close(handle);
    return 3;
  }
  if (nfq_set_queue_flags(context.queue, NFQA_CFG_F_FAIL_OPEN, NFQA_CFG_F_FAIL_OPEN) < 0) {
    std::fprintf(stderr, "auv_link_impair: warning: no fail-open on the kernel queue: %s\n",
                 std::strerror(errno));
  }
  nfnl_rcvbufsiz(nfq_nfnlh(handle), 8u << 20);
  const int fd = nfq_fd(handle);

  std::printf(
      "link_impair: queue %d ready: loss %g delay %g ms jitter %g ms reorder %g reorder-delay "
      "%g ms seed %u capacity %zu\n",
      options.queue, options.loss, options.delay_ms, options.jitter_ms, options.reorder,
      options.reorder_delay_ms, options.seed, options.capacity);

  const int64_t stats_every_us = static_cast<int64_t>(options.stats_every_s * 1e6);
  int64_t next_stats = stats_every_us > 0 ? nowUs() + stats_every_us : INT64_MAX;
  uint64_t netlink_lost = 0;
  int exit_code = 0;
  std::vector<char> buffer(1 << 16);
  while (g_signal == 0) {
    int64_t now = nowUs();
    releaseDue(&context, now);
    if (now >= next_stats) {
      printCounters("stats", context, netlink_lost);
      next_stats = now + stats_every_us;
    }
    int64_t wake = next_stats;
    if (const auto release = impairer.nextRelease()) wake = std::min(wake, *release);
    timespec timeout{};
    timespec* timeout_pointer = nullptr;
    if (wake != INT64_MAX) {
      const int64_t wait = std::max<int64_t>(0, wake - now);
      timeout.tv_sec = wait / 1000000;
      timeout.tv_nsec = (wait % 1000000) * 1000;
      timeout_pointer = &timeout;
    }
    pollfd poll_fd{fd, POLLIN, 0};
    const int ready = ppoll(&poll_fd, 1, timeout_pointer, &during_wait);
    if (ready < 0 && errno != EINTR) {
      std::fprintf(stderr, "auv_link_impair: poll: %s\n", std::strerror(errno));
      exit_code = 1;
      break;
    }
    if (ready <= 0) continue;
    bool fatal = false;
    for (;;) {  // everything queued now
      const ssize_t n = recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
      if (n >= 0) {
        nfq_handle_packet(handle, buffer.data(), static_cast<int>(n));
        continue;
      }
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) break;
      if (errno == ENOBUFS) {  // the kernel dropped messages: those packets stay queued
        if (netlink_lost++ == 0) {
          std::fprintf(stderr, "auv_link_impair: netlink receive buffer overrun\n");
        }
        continue;
      }
      std::fprintf(stderr, "auv_link_impair: recv: %s\n", std::strerror(errno));
      fatal = true;
      break;
    }
    if (fatal) {
      exit_code = 1;
      break;
    }
  }

  // Never strand a packet: destroying the queue would drop what it holds, so accept the held
  // packets and whatever is still queued first.
  context.ids.clear();
  impairer.takeAll(&context.ids);
  for (uint32_t id : context.ids) issue(&context, id, NF_ACCEPT);
  context.draining = true;
  for (ssize_t n; (n = recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT)) > 0;) {
    nfq_handle_packet(handle, buffer.data(), static_cast<int>(n));
  }
  const char* when = g_signal == SIGINT    ? "exit (SIGINT)"
                     : g_signal == SIGTERM ? "exit (SIGTERM)"
                                           : "exit (error)";
  printCounters(when, context, netlink_lost);
  nfq_destroy_queue(context.queue);
  nfq_close(handle);
  return exit_code;
}
