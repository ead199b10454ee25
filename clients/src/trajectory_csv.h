#pragma once
/// \file
/// Writes a JointTrajectory as CSV: t, q_<joint>…, qd_<joint>…, qdd_<joint>…

#include <ostream>

#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// One header line, then one line per point. Numbers round-trip (17 significant digits).
void WriteTrajectoryCsv(const v1::JointTrajectory& trajectory, std::ostream& out);

}  // namespace chasles
