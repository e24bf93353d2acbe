// Results a process keeps instead of computing again (parsed metadata, a census, balanced
// partitions): a few values by key, the oldest dropped first, shared between threads. A value is
// computed outside the lock, so two threads may each compute one key once.
#pragma once

#include <algorithm>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace exa {

template <typename T> class KeptResults {
public:
  explicit KeptResults(size_t capacity) : capacity_(std::max<size_t>(capacity, 1)) {}
  KeptResults(const KeptResults&) = delete;
  KeptResults& operator=(const KeptResults&) = delete;

  /// The value kept under `key` for which `stillValid(value)` holds, or null.
  template <typename Valid> std::shared_ptr<const T> find(const std::string& key, Valid&& stillValid) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [k, value] : kept_)
      if (k == key && stillValid(*value)) return value;
    return nullptr;
  }
  std::shared_ptr<const T> find(const std::string& key) const {
    return find(key, [](const T&) { return true; });
  }

  /// Keeps `value` under `key`, in place of any value kept under it.
  std::shared_ptr<const T> keep(const std::string& key, T value) {
    auto shared = std::make_shared<const T>(std::move(value));
    const std::lock_guard<std::mutex> lock(mutex_);
    std::erase_if(kept_, [&](const auto& k) { return k.first == key; });
    if (kept_.size() >= capacity_) kept_.erase(kept_.begin());
    kept_.emplace_back(key, shared);
    return shared;
  }

private:
  size_t capacity_;
  mutable std::mutex mutex_;
  std::vector<std::pair<std::string, std::shared_ptr<const T>>> kept_;
};

} // namespace exa
