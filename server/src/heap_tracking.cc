// Replacement of the global operator new/delete (C++17 [new.delete]): every form allocates with
// malloc (aligned_alloc for over-aligned types) and, inside a HeapScope, adds the block's usable
// size to the thread's counter; delete subtracts it. Outside a scope the cost is one
// thread-local load per call.
#include "chasles/server/heap_tracking.h"

#include <malloc.h>

#include <cstdlib>
#include <new>

namespace chasles {
namespace {

// Static TLS: the counter pointer is read on every allocation of the process.
thread_local HeapCounter* t_counter __attribute__((tls_model("initial-exec"))) = nullptr;

/// Throws std::bad_alloc when a block of `size` bytes would take the scope over its limit.
inline void CheckLimit(std::size_t size) {
  for (HeapCounter* c = t_counter; c; c = c->outer) {
    if (c->limit > 0 && c->live + static_cast<std::int64_t>(size) > c->limit) {
      c->exceeded = true;
      throw std::bad_alloc();
    }
  }
}

inline void CountAlloc(void* p) {
  if (HeapCounter* c = t_counter) {
    const auto bytes = static_cast<std::int64_t>(malloc_usable_size(p));
    for (; c; c = c->outer) {
      c->live += bytes;
      if (c->live > c->peak) c->peak = c->live;
    }
  }
}

inline void CountFree(void* p) {
  if (HeapCounter* c = t_counter) {
    const auto bytes = static_cast<std::int64_t>(malloc_usable_size(p));
    for (; c; c = c->outer) c->live -= bytes;
  }
}

void* Allocate(std::size_t size) {
  if (size == 0) size = 1;
  CheckLimit(size);
  for (;;) {
    if (void* p = std::malloc(size)) {
      CountAlloc(p);
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

void* AllocateAligned(std::size_t size, std::align_val_t alignment) {
  const std::size_t align = static_cast<std::size_t>(alignment);
  if (size == 0) size = 1;
  CheckLimit(size);
  for (;;) {
    void* p = nullptr;
    if (posix_memalign(&p, align < sizeof(void*) ? sizeof(void*) : align, size) == 0) {
      CountAlloc(p);
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

void Release(void* p) noexcept {
  if (!p) return;
  CountFree(p);
  std::free(p);
}

}  // namespace

HeapScope::HeapScope(std::uint64_t limit_bytes) : previous_(t_counter) {
  counter_.limit = static_cast<std::int64_t>(limit_bytes);
  counter_.outer = previous_;
  t_counter = &counter_;
}
HeapScope::~HeapScope() { t_counter = previous_; }

void ReleaseFreeHeapMemory() { malloc_trim(0); }

void UseFixedMmapThreshold(std::size_t bytes) { mallopt(M_MMAP_THRESHOLD, static_cast<int>(bytes)); }

}  // namespace chasles

void* operator new(std::size_t size) { return chasles::Allocate(size); }
void* operator new[](std::size_t size) { return chasles::Allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return chasles::Allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return chasles::Allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t alignment) { return chasles::AllocateAligned(size, alignment); }
void* operator new[](std::size_t size, std::align_val_t alignment) { return chasles::AllocateAligned(size, alignment); }
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return chasles::AllocateAligned(size, alignment);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return chasles::AllocateAligned(size, alignment);
  } catch (...) {
    return nullptr;
  }
}

void operator delete(void* p) noexcept { chasles::Release(p); }
void operator delete[](void* p) noexcept { chasles::Release(p); }
void operator delete(void* p, std::size_t) noexcept { chasles::Release(p); }
void operator delete[](void* p, std::size_t) noexcept { chasles::Release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { chasles::Release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { chasles::Release(p); }
void operator delete(void* p, std::align_val_t) noexcept { chasles::Release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { chasles::Release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { chasles::Release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { chasles::Release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { chasles::Release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { chasles::Release(p); }
