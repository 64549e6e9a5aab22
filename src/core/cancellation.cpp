#include "skytrace/core/cancellation.hpp"

#include <atomic>
#include <csignal>
#include <cstring>
#include <unistd.h>
#include <string>

namespace skytrace {
namespace {

std::atomic<int> g_signal{0};

extern "C" void on_cancellation_signal(int signal_number) {
  int expected = 0;
  if (!g_signal.compare_exchange_strong(expected, signal_number)) {
    // Second signal: the user insists; default action (the next run removes the staging folder).
    std::signal(signal_number, SIG_DFL);
    std::raise(signal_number);
  }
}

extern "C" void on_live_stop_signal(int signal_number) {
  on_cancellation_signal(signal_number);
  alarm(1);  // async-signal-safe; the default action of SIGALRM ends the process
}

void install_handler(void (*handler)(int)) {
  struct sigaction action {};
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR and their loops look at the flag
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace

void install_live_stop_handlers() {
  std::signal(SIGALRM, SIG_DFL);
  install_handler(on_live_stop_signal);
}

void disarm_stop_watchdog() { alarm(0); }

void install_cancellation_handlers() { install_handler(on_cancellation_signal); }

bool cancellation_requested() { return g_signal.load(std::memory_order_relaxed) != 0; }

std::optional<int> cancellation_signal() {
  const int s = g_signal.load(std::memory_order_relaxed);
  if (s == 0) return std::nullopt;
  return s;
}

void request_cancellation(int signal_number) {
  int expected = 0;
  g_signal.compare_exchange_strong(expected, signal_number);
}

void reset_cancellation() { g_signal.store(0); }

Error cancelled_error() {
  const int s = g_signal.load();
  const char* name = s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : s == SIGHUP ? "SIGHUP" : "a signal";
  return make_error(ErrorCode::kCancelled, std::string("stopped by ") + name + " before the end; no outputs written");
}

}  // namespace skytrace
