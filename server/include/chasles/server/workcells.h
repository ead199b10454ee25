#pragma once
/// \file
/// Workcell reservations: trajectories committed by a long-running coordinator, which later
/// planning requests in the same workcell avoid in space and time. The state lives in this
/// process (one replica; lost on restart) or, with the shared store, in Redis. Thread-safe.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "chasles/multi/coordinator.h"
#include "chasles/server/redis_client.h"

namespace chasles {

/// One committed trajectory. Times are on the workcell clock [s since the Unix epoch].
struct Reservation {
  std::string id;          ///< "<workcell>/<n>"
  std::string robot_name;
  PlacedRobot placement;   ///< placement.name == robot_name
  TimedTrajectory trajectory;
  /// What another replica rebuilds it from (the shared store): the CommitTrajectoryRequest as
  /// committed, robot by id, start_time resolved. Empty with the memory store.
  std::string record;
  double start_time = 0.0;  ///< trajectory's t = 0
  double end_time = 0.0;    ///< start_time + duration
  double expires_at = 0.0;  ///< end_time + hold: the robot occupies its final configuration until then
};

/// How much a WorkcellStore may hold (each committed trajectory piece costs about 1 KB).
struct WorkcellLimits {
  std::size_t max_workcells = 1024;
  std::size_t max_pieces_per_workcell = 500000;  ///< pieces of the active reservations together
};

/// Where workcells and their reservations live. By default in this process (lost on restart,
/// not seen by other replicas); with UseShared, in Redis: every replica sharing the store sees
/// the same workcells and reservations, a commit is atomic across replicas (WATCH/MULTI/EXEC on
/// the workcell's version, retried when another replica wrote meanwhile), and a reservation's
/// record expires with it (a Redis TTL at expires_at). Replicas compare reservations against
/// their own clocks, which must agree (NTP).
class WorkcellStore {
 public:
  /// Rebuilds a reservation from its record (robot resolved, trajectory rebuilt; id, end_time and
  /// expires_at filled in).
  using ReservationLoader = std::function<Reservation(const std::string& record)>;
  static constexpr const char* kWorkcellsKey = "chasles:workcells";

  /// The clock [s since the Unix epoch]; the default reads the system clock. Tests inject theirs.
  using Clock = std::function<double()>;
  explicit WorkcellStore(Clock clock = {}, WorkcellLimits limits = {});

  double Now() const { return clock_(); }

  /// Creates the workcell; false when it existed already.
  /// \throws Error(kInvalidArgument) for a name outside [A-Za-z0-9_.-]{1,64};
  ///         Error(kResourceExhausted) when max_workcells exist already.
  bool Create(const std::string& name);

  /// The reservations not yet expired (expired ones are dropped), in commit order.
  /// \throws Error(kNotFound) naming the workcell and listing the known ones.
  std::vector<Reservation> Active(const std::string& workcell);

  /// Commits `reservation` (id, end_time and expires_at are filled in and returned) after checking
  /// it against every active reservation of other robots (robot against robot, `padding` [m] around
  /// both, at ≤ 1 ms and ≤ 0.005 rad) and that the same robot's reservations do not overlap in time.
  /// \throws Error(kNotFound) for an unknown workcell; Error(kFailedPrecondition) naming the
  ///         reservation, robots, links and time of a conflict; Error(kResourceExhausted) when the
  ///         workcell's active reservations would hold more than max_pieces_per_workcell pieces.
  Reservation Commit(const std::string& workcell, Reservation reservation, double hold, double padding);

  /// Releases one reservation by id, or every reservation of `robot_name` when the id is empty.
  /// Returns how many were released. \throws Error(kNotFound) for an unknown workcell or id;
  /// Error(kInvalidArgument) when both id and robot_name are empty.
  int Release(const std::string& workcell, const std::string& reservation_id, const std::string& robot_name);

  /// Active reservations of the workcell (0 for an unknown one).
  int ActiveCount(const std::string& workcell);

  /// Keeps workcells and reservations in Redis from now on (before serving).
  void UseShared(std::shared_ptr<RedisClient> redis, ReservationLoader load);

 private:
  void CheckCommit(const std::string& workcell, const std::vector<Reservation>& others, std::uint64_t number,
                   double hold, double padding, Reservation* reservation) const;
  std::vector<Reservation> ReadShared(const std::string& workcell, RedisClient::Held& redis);
  Reservation CommitShared(const std::string& workcell, Reservation reservation, double hold, double padding);
  int ReleaseShared(const std::string& workcell, const std::string& reservation_id, const std::string& robot_name);

  struct Cell {
    std::mutex mutex;  ///< serialises commits, so two conflicting commits cannot both succeed
    std::vector<Reservation> reservations;
    std::uint64_t next_id = 1;
  };
  Cell& Find(const std::string& workcell);  ///< \throws kNotFound
  static void DropExpired(Cell& cell, double now);

  Clock clock_;
  WorkcellLimits limits_;
  std::mutex mutex_;  ///< guards cells_ (the map, not the cells' contents)
  std::map<std::string, std::unique_ptr<Cell>> cells_;
  std::shared_ptr<RedisClient> redis_;
  ReservationLoader load_;
  std::mutex loaded_mutex_;
  std::map<std::string, Reservation> loaded_;  ///< shared reservations rebuilt here, by id
};

/// A reservation's motion on a time line whose t = 0 is `origin` [s since epoch].
CommittedMotion MotionOf(const Reservation& reservation, double origin);

}  // namespace chasles
