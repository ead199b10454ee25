#pragma once
/// \file
/// A thread-safe least-recently-used cache of shared immutable values, bounded in bytes.

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>

#include "chasles/server/request_record.h"

namespace chasles {

/// Maps string keys to `shared_ptr<const T>` of any T (the caller keeps key spaces apart, e.g.
/// "robot:…", "scene:…"), each with its estimated size in bytes. The entries' sizes add up to
/// at most `capacity_bytes`: inserting evicts least recently used entries until the new one
/// fits. A value larger than the whole capacity is returned but not kept. Callers that still
/// hold an evicted pointer keep it alive. All methods are thread-safe.
class LruCache {
 public:
  explicit LruCache(std::uint64_t capacity_bytes) : capacity_(capacity_bytes) {}

  /// The value for `key`, or nullptr. Marks it most recently used. T must be the type it was
  /// stored with.
  template <typename T>
  std::shared_ptr<const T> Get(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = index_.find(key);
    if (it == index_.end()) return nullptr;
    order_.splice(order_.begin(), order_, it->second);
    return std::static_pointer_cast<const T>(it->second->value);
  }

  /// Stores `value` of `bytes` under `key` and returns the stored value. When another thread
  /// stored the key first, keeps and returns that one.
  template <typename T>
  std::shared_ptr<const T> Put(const std::string& key, std::shared_ptr<const T> value, std::uint64_t bytes) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = index_.find(key);
    if (it != index_.end()) {
      order_.splice(order_.begin(), order_, it->second);
      return std::static_pointer_cast<const T>(it->second->value);
    }
    if (bytes > capacity_) return value;  // too large to keep: the caller uses it once
    while (!order_.empty() && bytes_ + bytes > capacity_) EvictOldest();
    order_.push_front(Entry{key, value, bytes});
    index_[key] = order_.begin();
    bytes_ += bytes;
    return value;
  }

  CacheStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    CacheStats stats;
    stats.entries = order_.size();
    stats.bytes = bytes_;
    stats.capacity_bytes = capacity_;
    stats.evictions = evictions_;
    return stats;
  }
  std::size_t size() const { return static_cast<std::size_t>(stats().entries); }

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const void> value;
    std::uint64_t bytes = 0;
  };
  void EvictOldest() {
    bytes_ -= order_.back().bytes;
    index_.erase(order_.back().key);
    order_.pop_back();
    ++evictions_;
  }

  const std::uint64_t capacity_;
  mutable std::mutex mutex_;
  std::list<Entry> order_;  ///< most recently used first
  std::unordered_map<std::string, std::list<Entry>::iterator> index_;
  std::uint64_t bytes_ = 0;
  std::uint64_t evictions_ = 0;
};

}  // namespace chasles
