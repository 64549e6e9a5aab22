// The node's log lines, in rclcpp's console format ("[WARN] [1700000000.123456789] [skytrace]:
// text") on stderr, so that a ROS 2 user reads them as any node's. Thread-safe: DDS listeners log
// from Cyclone's threads.
#pragma once

#include <fmt/format.h>

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace skytrace::ros2_node {

enum class LogLevel { kDebug, kInfo, kWarn, kError, kFatal };

class Log {
 public:
  explicit Log(std::string name = "skytrace") : name_(std::move(name)) {}
  void set_name(std::string name) {
    const std::lock_guard lock(mutex_);
    name_ = std::move(name);
  }
  void write(LogLevel level, std::string_view text);
  // At most once per `period_s` for one `key` (the warnings of a loop that runs at 100 Hz).
  void throttled(LogLevel level, double period_s, std::string_view key, std::string_view text);

  template <typename... Args>
  void info(fmt::format_string<Args...> format, Args&&... args) {
    write(LogLevel::kInfo, fmt::format(format, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void warn(fmt::format_string<Args...> format, Args&&... args) {
    write(LogLevel::kWarn, fmt::format(format, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void error(fmt::format_string<Args...> format, Args&&... args) {
    write(LogLevel::kError, fmt::format(format, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void fatal(fmt::format_string<Args...> format, Args&&... args) {
    write(LogLevel::kFatal, fmt::format(format, std::forward<Args>(args)...));
  }

 private:
  std::mutex mutex_;
  std::string name_;
  std::map<std::string, std::chrono::steady_clock::time_point, std::less<>> last_;
};

}  // namespace skytrace::ros2_node
