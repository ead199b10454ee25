#pragma once
/// \file
/// Per-thread heap accounting for benchmark runs. This library replaces the global operator
/// new/delete (every form) with malloc/free plus a thread-local counter that is live only inside
/// a HeapScope, so a run's peak heap use can be measured while other runs execute on other
/// threads. What is counted: blocks obtained through operator new on the scope's thread
/// (OMPL's states and graphs, FCL's objects, standard containers), at their malloc_usable_size.
/// What is not: memory from malloc directly (Eigen's buffers, C libraries), and blocks other
/// threads allocate for the run.

#include <cstdint>

namespace chasles {

/// Live and peak bytes of one scope. Not thread-safe: owned by one thread.
struct HeapCounter {
  std::int64_t live = 0;  ///< allocated − freed since the scope began [bytes] (can go below 0 when
                          ///< the scope frees blocks allocated before it)
  std::int64_t peak = 0;  ///< max of `live` [bytes], >= 0
};

/// Counts this thread's operator new/delete traffic from construction to destruction.
/// Scopes nest: an inner scope pauses the outer one's counting.
class HeapScope {
 public:
  HeapScope();
  ~HeapScope();
  HeapScope(const HeapScope&) = delete;
  HeapScope& operator=(const HeapScope&) = delete;

  /// Peak bytes held above the scope's starting point so far.
  std::uint64_t peak_bytes() const { return static_cast<std::uint64_t>(counter_.peak); }
  std::int64_t live_bytes() const { return counter_.live; }

 private:
  HeapCounter counter_;
  HeapCounter* previous_;
};

}  // namespace chasles
