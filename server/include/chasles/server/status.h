#pragma once
/// \file
/// The one mapping from failures to gRPC status codes.

#include <exception>
#include <string>
#include <string_view>

#include <grpcpp/support/status.h>

#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/robot/error.h"

namespace chasles {

/// chasles::Error → INVALID_ARGUMENT / NOT_FOUND / FAILED_PRECONDITION with its message;
/// any other exception → INTERNAL with its message. Never UNKNOWN.
/// The message is passed through StatusMessage.
grpc::Status StatusFromException(std::exception_ptr error);
/// StatusFromException without the message clean-up.
grpc::Status StatusFromExceptionRaw(std::exception_ptr error);

/// A status message safe to send and print: control characters (NUL, ESC, newlines …) that a
/// client's text may have brought in are written as `\xHH`, and it is cut at 4 KiB.
std::string StatusMessage(std::string_view text);

/// The status of a finished pipeline run: OK for every expected outcome (the outcome is in the
/// response), CANCELLED / DEADLINE_EXCEEDED when the client cancelled or the deadline passed.
grpc::Status StatusFromOutcome(PlanOutcomeCode code, const std::string& message);

}  // namespace chasles
