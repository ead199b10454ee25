#include "chasles/server/workcells.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
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
  CheckName("name", name);
  if (redis_ != nullptr) {
    if (redis_->Command({"SISMEMBER", kWorkcellsKey, name}).integer == 1) return false;
    const long long count = redis_->Command({"SCARD", kWorkcellsKey}).integer;
    if (static_cast<std::size_t>(count) >= limits_.max_workcells) {
      ThrowResourceExhausted("the shared store holds " + std::to_string(count) +
                             " workcells already, the server's cap; reuse one (workcells live as long as the store)");
    }
    return redis_->Command({"SADD", kWorkcellsKey, name}).integer == 1;
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
  if (redis_ != nullptr) {
    std::vector<Reservation> active;
    redis_->Transaction([&](RedisClient::Held& redis) { active = ReadShared(workcell, redis); });
    return active;
  }
  Cell& cell = Find(workcell);
  std::lock_guard<std::mutex> lock(cell.mutex);
  DropExpired(cell, Now());
  return cell.reservations;
}

/// Fills in reservation's end_time, expires_at and id (`workcell/<number>`) and checks it against
/// the active reservations `others` (see Commit).
void WorkcellStore::CheckCommit(const std::string& workcell, const std::vector<Reservation>& others,
                                std::uint64_t number, double hold, double padding, Reservation* reservation) const {
  std::size_t pieces = reservation->trajectory.pieces().size();
  for (const Reservation& other : others) pieces += other.trajectory.pieces().size();
  if (pieces > limits_.max_pieces_per_workcell) {
    ThrowResourceExhausted("workcell '" + workcell + "' would hold " + std::to_string(pieces) +
                           " trajectory pieces in its active reservations, more than the server's cap of " +
                           std::to_string(limits_.max_pieces_per_workcell) +
                           "; commit coarser trajectories or release finished ones");
  }
  reservation->placement.name = reservation->robot_name;
  reservation->end_time = reservation->start_time + reservation->trajectory.duration();
  reservation->expires_at = reservation->end_time + hold;
  reservation->id = workcell + "/" + std::to_string(number);
  const double origin = reservation->start_time;
  const CommittedMotion mine = MotionOf(*reservation, origin);
  for (const Reservation& other : others) {
    if (other.robot_name == reservation->robot_name) {
      if (other.start_time < reservation->expires_at && reservation->start_time < other.expires_at) {
        throw Error(ErrorCode::kFailedPrecondition,
                    "robot '" + reservation->robot_name + "' already holds reservation '" + other.id + "' from " +
                        EpochText(other.start_time) + " to " + EpochText(other.expires_at) +
                        " s, which overlaps this one (" + EpochText(reservation->start_time) + " to " +
                        EpochText(reservation->expires_at) + " s); release it first");
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
}

Reservation WorkcellStore::Commit(const std::string& workcell, Reservation reservation, double hold, double padding) {
  if (!std::isfinite(hold) || hold < 0.0 || hold > 86400.0) {
    ThrowInvalid("hold = " + FormatNumber(hold) + " must be within [0, 86400] s");
  }
  if (!std::isfinite(padding) || padding < 0.0 || padding > 0.5) {
    ThrowInvalid("robot_padding = " + FormatNumber(padding) + " must be within [0, 0.5] m");
  }
  if (reservation.trajectory.empty()) ThrowInvalid("trajectory has no points");
  if (redis_ != nullptr) return CommitShared(workcell, std::move(reservation), hold, padding);
  Cell& cell = Find(workcell);
  std::lock_guard<std::mutex> lock(cell.mutex);
  DropExpired(cell, Now());
  CheckCommit(workcell, cell.reservations, cell.next_id, hold, padding, &reservation);
  ++cell.next_id;
  cell.reservations.push_back(reservation);
  return reservation;
}

int WorkcellStore::Release(const std::string& workcell, const std::string& reservation_id,
                           const std::string& robot_name) {
  if (reservation_id.empty() && robot_name.empty()) {
    ThrowInvalid("reservation_id and robot_name are both empty: name the reservation or the robot to release");
  }
  if (redis_ != nullptr) return ReleaseShared(workcell, reservation_id, robot_name);
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
  if (redis_ != nullptr) {
    if (redis_->Command({"SISMEMBER", kWorkcellsKey, workcell}).integer != 1) return 0;
    return static_cast<int>(Active(workcell).size());
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!cells_.count(workcell)) return 0;
  }
  return static_cast<int>(Active(workcell).size());
}

// --- the shared store (Redis) --------------------------------------------------------------------
//
// Keys: kWorkcellsKey, a set of workcell names; per workcell W, "chasles:wc:W:ids" (the ids of its
// reservations), "chasles:wc:W:r:<id>" (a reservation's record, expiring with the reservation:
// Redis deletes it at expires_at), "chasles:wc:W:version" (bumped by every commit and release)
// and "chasles:wc:W:next" (the reservation numbers). A commit WATCHes the version, reads the
// active reservations, checks against them, and writes in MULTI … EXEC: when another replica
// committed or released meanwhile, EXEC fails and the commit starts over with what is there now.

namespace {

std::string CellKey(const std::string& workcell, const std::string& what) { return "chasles:wc:" + workcell + ":" + what; }

std::uint64_t NumberOf(const std::string& id) {
  const std::size_t slash = id.rfind('/');
  return slash == std::string::npos ? 0 : std::strtoull(id.c_str() + slash + 1, nullptr, 10);
}

}  // namespace

void WorkcellStore::UseShared(std::shared_ptr<RedisClient> redis, ReservationLoader load) {
  redis_ = std::move(redis);
  load_ = std::move(load);
}

std::vector<Reservation> WorkcellStore::ReadShared(const std::string& workcell, RedisClient::Held& redis) {
  const std::vector<RedisReply> first =
      redis.Pipeline({{"SISMEMBER", kWorkcellsKey, workcell}, {"SMEMBERS", CellKey(workcell, "ids")}});
  if (first[0].integer != 1) {
    std::string known;
    const RedisReply members = redis.Send({"SMEMBERS", kWorkcellsKey});
    for (const RedisReply& name : members.elements) {
      known += (known.empty() ? "" : ", ") + name.str;
    }
    throw Error(ErrorCode::kNotFound, "workcell '" + workcell + "' is unknown (known: " +
                                          (known.empty() ? "none" : known) + "); create it with CreateWorkcell");
  }
  const RedisReply& ids = first[1];
  std::vector<Reservation> active;
  if (ids.elements.empty()) return active;
  std::vector<std::string> get = {"MGET"};
  for (const RedisReply& id : ids.elements) get.push_back(CellKey(workcell, "r:" + id.str));
  const RedisReply records = redis.Send(get);
  const double now = Now();
  std::lock_guard<std::mutex> lock(loaded_mutex_);
  for (std::size_t k = 0; k < ids.elements.size() && k < records.elements.size(); ++k) {
    const std::string& id = ids.elements[k].str;
    if (records.elements[k].nil()) continue;  // expired: Redis dropped its record
    auto it = loaded_.find(id);
    if (it == loaded_.end()) {
      Reservation r = load_(records.elements[k].str);
      r.id = id;
      it = loaded_.emplace(id, std::move(r)).first;
    }
    if (it->second.expires_at > now) active.push_back(it->second);
  }
  std::sort(active.begin(), active.end(),
            [](const Reservation& a, const Reservation& b) { return NumberOf(a.id) < NumberOf(b.id); });
  return active;
}

Reservation WorkcellStore::CommitShared(const std::string& workcell, Reservation reservation, double hold,
                                        double padding) {
  if (reservation.record.empty()) throw Error(ErrorCode::kFailedPrecondition, "the reservation has no record to share");
  for (int attempt = 0; attempt < 100; ++attempt) {
    bool committed = false;
    Reservation candidate = reservation;
    redis_->Transaction([&](RedisClient::Held& redis) {
      redis.Send({"WATCH", CellKey(workcell, "version")});
      const std::vector<Reservation> others = ReadShared(workcell, redis);
      const std::uint64_t number = static_cast<std::uint64_t>(redis.Send({"INCR", CellKey(workcell, "next")}).integer);
      CheckCommit(workcell, others, number, hold, padding, &candidate);
      const long long expires_ms = static_cast<long long>(std::ceil(candidate.expires_at * 1e3));
      const std::vector<RedisReply> replies = redis.Pipeline(
          {{"MULTI"},
           {"SET", CellKey(workcell, "r:" + candidate.id), candidate.record, "PXAT", std::to_string(expires_ms)},
           {"SADD", CellKey(workcell, "ids"), candidate.id},
           {"INCR", CellKey(workcell, "version")},
           {"EXEC"}});
      committed = !replies.back().nil();  // nil: the version changed since WATCH
    });
    if (committed) {
      std::lock_guard<std::mutex> lock(loaded_mutex_);
      loaded_[candidate.id] = candidate;
      return candidate;
    }
  }
  throw Error(ErrorCode::kUnavailable, "workcell '" + workcell +
                                           "' changed under this commit 100 times in a row; try again");
}

int WorkcellStore::ReleaseShared(const std::string& workcell, const std::string& reservation_id,
                                 const std::string& robot_name) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    int released = -1;
    redis_->Transaction([&](RedisClient::Held& redis) {
      redis.Send({"WATCH", CellKey(workcell, "version")});
      const std::vector<Reservation> active = ReadShared(workcell, redis);
      std::vector<std::string> ids;
      for (const Reservation& r : active) {
        if (reservation_id.empty() ? r.robot_name == robot_name : r.id == reservation_id) ids.push_back(r.id);
      }
      if (!reservation_id.empty() && ids.empty()) {
        throw Error(ErrorCode::kNotFound, "reservation_id = '" + reservation_id +
                                              "' is not an active reservation of workcell '" + workcell +
                                              "' (released, expired or never committed)");
      }
      std::vector<std::vector<std::string>> commands = {{"MULTI"}};
      for (const std::string& id : ids) {
        commands.push_back({"DEL", CellKey(workcell, "r:" + id)});
        commands.push_back({"SREM", CellKey(workcell, "ids"), id});
      }
      commands.push_back({"INCR", CellKey(workcell, "version")});
      commands.push_back({"EXEC"});
      if (!redis.Pipeline(commands).back().nil()) released = static_cast<int>(ids.size());
    });
    if (released >= 0) return released;
  }
  throw Error(ErrorCode::kUnavailable, "workcell '" + workcell + "' changed under this release 100 times in a row; try again");
}

}  // namespace chasles
