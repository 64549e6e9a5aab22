// Cooperative cancellation by signal: the command-line tools install the handlers, long loops ask
// `cancellation_requested()` and unwind with ErrorCode::kCancelled, so that destructors remove
// staging folders and temporary files. A second signal ends the process at once.
#pragma once

#include <optional>

#include "skytrace/core/error.hpp"

namespace skytrace {

// Installs handlers for SIGINT, SIGTERM and SIGHUP and ignores SIGXFSZ (a write beyond the file
// size limit then fails with EFBIG and is reported like a full disk, instead of killing the
// process with its outputs half-written).
void install_cancellation_handlers();

// True once one of those signals has arrived (or request_cancellation was called).
[[nodiscard]] bool cancellation_requested();
// The signal that asked for cancellation, if any.
[[nodiscard]] std::optional<int> cancellation_signal();
// Asks for cancellation as the signal handler does (async-signal-safe); for tests.
void request_cancellation(int signal_number);
// Forgets a request (tests only).
void reset_cancellation();

// For live loops (skytrace serve and gz, the ROS nodes): the handlers above, plus a watchdog: should
// the loop not end within a second of the signal (a step that does not return, a DDS call or a ROS
// master that hangs), SIGALRM ends the process, so that SIGINT and SIGTERM always end it promptly.
// A second signal ends it at once, as above.
void install_live_stop_handlers();
// Called once the loop has ended in time, before the outputs are finished (no forced exit then).
void disarm_stop_watchdog();

// kCancelled naming the signal, for loops that stop.
[[nodiscard]] Error cancelled_error();

}  // namespace skytrace
