#include "log.hpp"

#include <cstdio>

namespace skytrace::ros2_node {
namespace {

std::string_view level_name(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "DEBUG";
    case LogLevel::kInfo: return "INFO";
    case LogLevel::kWarn: return "WARN";
    case LogLevel::kError: return "ERROR";
    case LogLevel::kFatal: return "FATAL";
  }
  return "INFO";
}

}  // namespace

void Log::write(LogLevel level, std::string_view text) {
  const auto since_epoch = std::chrono::system_clock::now().time_since_epoch();
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(since_epoch).count();
  const std::lock_guard lock(mutex_);
  std::fputs(fmt::format("[{}] [{}.{:09d}] [{}]: {}\n", level_name(level), ns / 1000000000, ns % 1000000000, name_, text)
                 .c_str(),
             stderr);
  std::fflush(stderr);
}

void Log::throttled(LogLevel level, double period_s, std::string_view key, std::string_view text) {
  const auto now = std::chrono::steady_clock::now();
  {
    const std::lock_guard lock(mutex_);
    auto it = last_.find(key);
    if (it != last_.end() && std::chrono::duration<double>(now - it->second).count() < period_s) return;
    last_.insert_or_assign(std::string(key), now);
  }
  write(level, text);
}

}  // namespace skytrace::ros2_node
