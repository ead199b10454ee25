#include "chasles/server/workcells.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <utility>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

double SystemNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// Workcell clock time with millisecond digits (FormatNumber's 6 significant digits would drop them).
std::string EpochText(double seconds) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.3f", seconds);
  return buffer;
}

}  // namespace

bool ValidWorkcellName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
           c == '-';
  });
}

CommittedMotion MotionOf(const Reservation& reservation, double origin) {
  CommittedMotion motion;
  motion.id = "reservation '" + reservation.id + "' (robot '" + reservation.robot_name + "')";
  motion.placement = reservation.placement;
  motion.trajectory = reservation.trajectory;
  motion.begin = reservation.start_time - origin;
  motion.until = reservation.expires_at - origin;
  return motion;
}

WorkcellStore::WorkcellStore(Clock clock, WorkcellLimits limits)
    : clock_(clock ? std::move(clock) : Clock(SystemNow)), limits_(limits) {}

bool WorkcellStore::Create(const std::string& name) {
  if (!ValidWorkcellName(name)) {
    ThrowInvalid("name = '" + name + "' must be 1 to 64 characters of [A-Za-z0-9_.-]");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (cells_.count(name) == 0 && cells_.size() >= limits_.max_workcells) {
    ThrowResourceExhausted("this server holds " + std::to_string(cells_.size()) +
                           " workcells already, its cap; reuse one (workcells live as long as the server)");
  }
  return cells_.emplace(name, std::make_unique<Cell>()).second;
}

WorkcellStore::Cell& WorkcellStore::Find(const std::string& workcell) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = cells_.find(workcell);
  if (it == cells_.end()) {
    std::string known;
    for (const auto& [name, cell] : cells_) known += (known.empty() ? "" : ", ") + name;
    throw Error(ErrorCode::kNotFound, "workcell '" + workcell + "' is unknown (known: " +
                                          (known.empty() ? "none" : known) + "); create it with CreateWorkcell");
  }
  return *it->second;
}

void WorkcellStore::DropExpired(Cell& cell, double now) {
  cell.reservations.erase(std::remove_if(cell.reservations.begin(), cell.reservations.end(),
                                         [now](const Reservation& r) { return r.expires_at <= now; }),
                          cell.reservations.end());
}

std::vector<Reservation> WorkcellStore::Active(const std::string& workcell) {
  Cell& cell = Find(workcell);
  std::lock_guard<std::mutex> lock(cell.mutex);
  DropExpired(cell, Now());
  return cell.reservations;
}

Reservation WorkcellStore::Commit(const std::string& workcell, Reservation reservation, double hold, double padding) {
  if (!std::isfinite(hold) || hold < 0.0 || hold > 86400.0) {
    ThrowInvalid("hold = " + FormatNumber(hold) + " must be within [0, 86400] s");
  }
  if (!std::isfinite(padding) || padding < 0.0 || padding > 0.5) {
    ThrowInvalid("robot_padding = " + FormatNumber(padding) + " must be within [0, 0.5] m");
  }
  if (reservation.trajectory.empty()) ThrowInvalid("trajectory has no points");
  Cell& cell = Find(workcell);
  std::lock_guard<std::mutex> lock(cell.mutex);
  DropExpired(cell, Now());
  std::size_t pieces = reservation.trajectory.pieces().size();
  for (const Reservation& other : cell.reservations) pieces += other.trajectory.pieces().size();
  if (pieces > limits_.max_pieces_per_workcell) {
    ThrowResourceExhausted("workcell '" + workcell + "' would hold " + std::to_string(pieces) +
                           " trajectory pieces in its active reservations, more than the server's cap of " +
                           std::to_string(limits_.max_pieces_per_workcell) +
                           "; commit coarser trajectories or release finished ones");
  }
  reservation.placement.name = reservation.robot_name;
  reservation.end_time = reservation.start_time + reservation.trajectory.duration();
  reservation.expires_at = reservation.end_time + hold;
  reservation.id = workcell + "/" + std::to_string(cell.next_id);
  const double origin = reservation.start_time;
  const CommittedMotion mine = MotionOf(reservation, origin);
  for (const Reservation& other : cell.reservations) {
    if (other.robot_name == reservation.robot_name) {
      if (other.start_time < reservation.expires_at && reservation.start_time < other.expires_at) {
        throw Error(ErrorCode::kFailedPrecondition,
                    "robot '" + reservation.robot_name + "' already holds reservation '" + other.id + "' from " +
                        EpochText(other.start_time) + " to " + EpochText(other.expires_at) +
                        " s, which overlaps this one (" + EpochText(reservation.start_time) + " to " +
                        EpochText(reservation.expires_at) + " s); release it first");
      }
      continue;
    }
    const std::string conflict = FindMotionConflict(mine, MotionOf(other, origin), 0.5 * padding);
    if (!conflict.empty()) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "the trajectory conflicts with a committed one: " + conflict +
                      " (t from this trajectory's start); plan it with workcell '" + workcell + "' to avoid it");
    }
  }
  ++cell.next_id;
  cell.reservations.push_back(reservation);
  return reservation;
}

int WorkcellStore::Release(const std::string& workcell, const std::string& reservation_id,
                           const std::string& robot_name) {
  if (reservation_id.empty() && robot_name.empty()) {
    ThrowInvalid("reservation_id and robot_name are both empty: name the reservation or the robot to release");
  }
  Cell& cell = Find(workcell);
  std::lock_guard<std::mutex> lock(cell.mutex);
  DropExpired(cell, Now());
  const auto before = cell.reservations.size();
  if (!reservation_id.empty()) {
    auto it = std::find_if(cell.reservations.begin(), cell.reservations.end(),
                           [&](const Reservation& r) { return r.id == reservation_id; });
    if (it == cell.reservations.end()) {
      throw Error(ErrorCode::kNotFound, "reservation_id = '" + reservation_id + "' is not an active reservation of workcell '" +
                                            workcell + "' (released, expired or never committed)");
    }
    cell.reservations.erase(it);
  } else {
    cell.reservations.erase(std::remove_if(cell.reservations.begin(), cell.reservations.end(),
                                           [&](const Reservation& r) { return r.robot_name == robot_name; }),
                            cell.reservations.end());
  }
  return static_cast<int>(before - cell.reservations.size());
}

int WorkcellStore::ActiveCount(const std::string& workcell) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!cells_.count(workcell)) return 0;
  }
  return static_cast<int>(Active(workcell).size());
}

}  // namespace chasles
