// quadify::core::Status — a small status value returned by every stage (modelled on leveldb's).
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

namespace quadify::core {

enum class StatusCode {
  kOk = 0,
  kInvalidInput,      // the input violates a documented precondition (bad mesh, bad options)
  kIoError,           // a file could not be read or written
  kNotConverged,      // an iterative method stopped before its tolerance
  kNumericalFailure,  // a factorization failed or a value became non-finite
  kInternal,          // a broken invariant: a bug
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status ok() { return Status(); }
  static Status invalid_input(std::string msg) { return Status(StatusCode::kInvalidInput, std::move(msg)); }
  static Status io_error(std::string msg) { return Status(StatusCode::kIoError, std::move(msg)); }
  static Status not_converged(std::string msg) { return Status(StatusCode::kNotConverged, std::move(msg)); }
  static Status numerical_failure(std::string msg) {
    return Status(StatusCode::kNumericalFailure, std::move(msg));
  }
  static Status internal(std::string msg) { return Status(StatusCode::kInternal, std::move(msg)); }

  bool is_ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "invalid input: <message>", or "ok".
  std::string to_string() const;

 private:
  Status(StatusCode code, std::string msg) : code_(code), message_(std::move(msg)) {}
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

const char* status_code_name(StatusCode code);

// Thrown by the readers and writers (I/O is the edge where exceptions are allowed). The message
// names the file and the problem, ready to print as one line.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A broken invariant (a bug, never bad input).
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

}  // namespace quadify::core

// QUADIFY_CHECK(cond, msg): throws InternalError when an invariant that must hold does not.
#define QUADIFY_CHECK(cond, msg)                                                              \
  do {                                                                                        \
    if (!(cond))                                                                              \
      throw ::quadify::core::InternalError(std::string(__FILE__) + ":" +                      \
                                           std::to_string(__LINE__) + ": " #cond ": " + (msg)); \
  } while (0)
