// Error values for I/O, parsing and loading. The library never prints: it returns these and the
// applications map them to log lines and exit codes.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

namespace skytrace {

enum class ErrorCode {
  kInvalidArgument,  // a value given by the user is out of range or malformed
  kParse,            // a file's content is malformed (message names file, line, field)
  kIo,               // a file could not be opened, read or written
  kNotFound,         // a requested item (satellite, ephemeris, model) does not exist
  kOutOfRange,       // a time or position is outside what the data covers
  kNetwork,          // a download failed
  kUnsupported,      // valid input that this version does not handle
  kOutput,           // an output could not be created or written (disk full, no permission, a folder)
  kCancelled,        // the user stopped the process (SIGINT, SIGTERM, SIGHUP) before it finished
};

struct Error {
  ErrorCode code = ErrorCode::kInvalidArgument;
  std::string message;

  // Prefixes context ("file.rnx:12: ") to the message, keeping the code.
  [[nodiscard]] Error with_context(const std::string& context) const {
    return Error{code, context + ": " + message};
  }
};

// Thrown by Result::value() on an error; carries the Error so callers can still inspect it.
class ErrorException : public std::runtime_error {
 public:
  explicit ErrorException(Error error) : std::runtime_error(error.message), error_(std::move(error)) {}
  [[nodiscard]] const Error& error() const { return error_; }

 private:
  Error error_;
};

// A small std::expected stand-in (C++20): either a value or an Error.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : storage_(std::move(value)) {}          // NOLINT(google-explicit-constructor)
  Result(Error error) : storage_(std::move(error)) {}      // NOLINT(google-explicit-constructor)

  [[nodiscard]] bool ok() const { return std::holds_alternative<T>(storage_); }
  explicit operator bool() const { return ok(); }

  T& value() & {
    if (!ok()) throw ErrorException(error());
    return std::get<T>(storage_);
  }
  const T& value() const& {
    if (!ok()) throw ErrorException(error());
    return std::get<T>(storage_);
  }
  T&& value() && {
    if (!ok()) throw ErrorException(error());
    return std::get<T>(std::move(storage_));
  }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  [[nodiscard]] const Error& error() const { return std::get<Error>(storage_); }

 private:
  std::variant<T, Error> storage_;
};

// Result for operations that return nothing on success.
struct Ok {};
using Status = Result<Ok>;

inline Error make_error(ErrorCode code, std::string message) { return Error{code, std::move(message)}; }

}  // namespace skytrace
