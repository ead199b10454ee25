#pragma once
/// \file
/// The one mapping from failures to gRPC status codes.

#include <exception>

#include <grpcpp/support/status.h>

#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/robot/error.h"

namespace chasles {

/// chasles::Error → INVALID_ARGUMENT / NOT_FOUND / FAILED_PRECONDITION with its message;
/// any other exception → INTERNAL with its message. Never UNKNOWN.
grpc::Status StatusFromException(std::exception_ptr error);

/// The status of a finished pipeline run: OK for every expected outcome (the outcome is in the
/// response), CANCELLED / DEADLINE_EXCEEDED when the client cancelled or the deadline passed.
grpc::Status StatusFromOutcome(PlanOutcomeCode code, const std::string& message);

}  // namespace chasles
