#pragma once
/// \file
/// Internal helpers of the optimizers module (not installed, not part of the API):
/// the piecewise-quadratic segment profile.

#include <cmath>
#include <sstream>
#include <string>

#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace optimizers_internal {


/// The three phases of a rest-to-rest segment profile.
enum class Phase { kAccelerate, kCruise, kDecelerate };

/// State of one segment at local time `tau` in [0, duration()], computed with the formulas of
/// the given phase (so a phase boundary can be evaluated from either side). Positions are
/// a + s·(b − a) in the acceleration and cruise phases and b − (1 − s)·(b − a) in the
/// deceleration phase, so τ = 0 gives `a` and τ = duration() gives `b` bit-exactly.
/// `sample.t` is set to seg.t0 + tau.
TrajectorySample SegmentStateInPhase(const TimedTrajectory::Segment& seg, Phase phase, double tau);

/// The phase that holds local time tau, taking the later phase at a boundary (right limit).
Phase PhaseAt(const TimedTrajectory::Segment& seg, double tau);

/// Duration [s] of a phase of the segment.
double PhaseDuration(const TimedTrajectory::Segment& seg, Phase phase);
/// Local start time [s] of a phase of the segment.
double PhaseStart(const TimedTrajectory::Segment& seg, Phase phase);

}  // namespace optimizers_internal
}  // namespace chasles
