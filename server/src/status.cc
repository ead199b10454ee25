#include "chasles/server/status.h"

#include <string>

namespace chasles {

std::string StatusMessage(std::string_view text) {
  constexpr std::size_t kMaxBytes = 4096;
  std::string out = EscapeControlCharacters(std::string(text.substr(0, kMaxBytes)));
  if (text.size() > kMaxBytes) out += "…(+" + std::to_string(text.size() - kMaxBytes) + " bytes)";
  return out;
}

grpc::Status StatusFromException(std::exception_ptr error) {
  grpc::Status status = StatusFromExceptionRaw(error);
  return grpc::Status(status.error_code(), StatusMessage(status.error_message()));
}

grpc::Status StatusFromExceptionRaw(std::exception_ptr error) {
  try {
    if (error) std::rethrow_exception(error);
    return grpc::Status(grpc::StatusCode::INTERNAL, "internal error: no exception to report");
  } catch (const Error& e) {
    switch (e.code()) {
      case ErrorCode::kInvalidArgument: return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, e.what());
      case ErrorCode::kNotFound: return grpc::Status(grpc::StatusCode::NOT_FOUND, e.what());
      case ErrorCode::kFailedPrecondition: return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION, e.what());
      case ErrorCode::kResourceExhausted: return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, e.what());
      case ErrorCode::kUnavailable: return grpc::Status(grpc::StatusCode::UNAVAILABLE, e.what());
    }
    return grpc::Status(grpc::StatusCode::INTERNAL, e.what());
  } catch (const std::bad_alloc&) {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory");
  } catch (const std::exception& e) {
    return grpc::Status(grpc::StatusCode::INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return grpc::Status(grpc::StatusCode::INTERNAL, "internal error: unknown exception");
  }
}

grpc::Status StatusFromOutcome(PlanOutcomeCode code, const std::string& message) {
  switch (code) {
    case PlanOutcomeCode::kCancelled:
      return grpc::Status(grpc::StatusCode::CANCELLED, message.empty() ? "cancelled by the client" : message);
    case PlanOutcomeCode::kDeadlineExceeded:
      return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                          message.empty() ? "the gRPC deadline passed before planning finished" : message);
    default:
      return grpc::Status::OK;
  }
}

}  // namespace chasles
