#include <libcore/status.h>

namespace quadify::core {

const char* status_code_name(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidInput: return "invalid input";
    case StatusCode::kIoError: return "I/O error";
    case StatusCode::kNotConverged: return "not converged";
    case StatusCode::kNumericalFailure: return "numerical failure";
    case StatusCode::kInternal: return "internal error";
  }
  return "unknown";
}

std::string Status::to_string() const {
  if (is_ok()) return "ok";
  return std::string(status_code_name(code_)) + ": " + message_;
}

}  // namespace quadify::core
