#pragma once
/// \file
/// Per-thread heap accounting for benchmark runs. This library replaces the global operator
/// new/delete (every form) with malloc/free plus a thread-local counter that is live only inside
/// a HeapScope, so a run's peak heap use can be measured while other runs execute on other
/// threads. What is counted: blocks obtained through operator new on the scope's thread
/// (OMPL's states and graphs, FCL's objects, standard containers), at their malloc_usable_size.
/// What is not: memory from malloc directly (Eigen's buffers, C libraries), and blocks other
/// threads allocate for the run.

#include <cstddef>
#include <cstdint>

namespace chasles {

/// Live and peak bytes of one scope. Not thread-safe: owned by one thread.
struct HeapCounter {
  std::int64_t live = 0;  ///< allocated − freed since the scope began [bytes] (can go below 0 when
                          ///< the scope frees blocks allocated before it)
  std::int64_t peak = 0;  ///< max of `live` [bytes], >= 0
  std::int64_t limit = 0; ///< 0 = none; else an operator new that would take `live` above it
                          ///< throws std::bad_alloc (nothrow forms return nullptr)
  bool exceeded = false;  ///< an allocation was refused for the limit
  HeapCounter* outer = nullptr;  ///< the enclosing scope's counter, which counts too
};

/// Counts this thread's operator new/delete traffic from construction to destruction.
/// Scopes nest: a block counts in its scope and in every enclosing one (and every limit on the
/// way holds).
/// With a limit, the scope is also a per-request memory cap: an operator new on this thread that
/// would hold more than `limit_bytes` above the scope's start throws std::bad_alloc, which the
/// server answers with RESOURCE_EXHAUSTED (see exceeded()).
class HeapScope {
 public:
  explicit HeapScope(std::uint64_t limit_bytes = 0);
  ~HeapScope();
  HeapScope(const HeapScope&) = delete;
  HeapScope& operator=(const HeapScope&) = delete;

  /// Peak bytes held above the scope's starting point so far.
  std::uint64_t peak_bytes() const { return static_cast<std::uint64_t>(counter_.peak); }
  std::int64_t live_bytes() const { return counter_.live; }
  /// True once an allocation was refused for the limit.
  bool exceeded() const { return counter_.exceeded; }
  std::uint64_t limit_bytes() const { return static_cast<std::uint64_t>(counter_.limit); }

 private:
  HeapCounter counter_;
  HeapCounter* previous_;
};

/// Gives freed heap memory back to the operating system (glibc malloc_trim on every arena).
/// The server calls it after a request whose peak was large, so RSS returns near its level
/// before the request.
void ReleaseFreeHeapMemory();

/// Makes large blocks come from mmap at a fixed threshold (glibc otherwise raises the threshold
/// after the first large free, keeping later large blocks on the heap after they are freed).
void UseFixedMmapThreshold(std::size_t bytes);

}  // namespace chasles
