// What the viewer's background work (movies, pictures) shares: random ids and tokens, and a job
// with its state, error, cancel flag and thread, kept in a table by id. A job is found only by
// the id made here.
#pragma once

#include <nlohmann/json.hpp>

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <utility>

namespace exa::view {

/// `digits` random hexadecimal digits (ids of jobs, the server's token).
inline std::string randomHex(int digits) {
  std::random_device device;
  std::string s;
  static const char* hex = "0123456789abcdef";
  for (int i = 0; i < digits; ++i)
    s += hex[device() & 15u];
  return s;
}

/// A job on its own thread: its state (set by the job, read by requests), error and cancel flag,
/// and the file it makes.
struct Job {
  std::string id = randomHex(24);
  std::string path; ///< the file it makes (served once the job is done)
  std::string name; ///< that file's name in a download
  std::atomic<bool> cancel{false};
  std::thread thread;

  /// What requests see of the job: id, state, error, and once it is done the file's size and its
  /// address (/api/KIND/file?id=ID).
  nlohmann::json describe(const std::string& kind) const {
    const std::string s = state(), why = error();
    nlohmann::json j{{"id", id}, {"state", s}};
    if (!why.empty()) j["error"] = why;
    if (s == "done") {
      std::error_code ec;
      j["bytes"] = std::filesystem::file_size(path, ec);
      j["file"] = "/api/" + kind + "/file?id=" + id;
    }
    return j;
  }

  void set(const std::string& s, const std::string& why = {}) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = s;
    error_ = why;
  }
  std::string state() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_;
  }
  std::string error() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return error_;
  }

private:
  mutable std::mutex mutex_;
  std::string state_ = "rendering", error_;
};

/// Jobs by id. The destructor cancels every job and waits for its thread.
template <typename J> class JobTable {
public:
  JobTable() = default;
  JobTable(const JobTable&) = delete;
  JobTable& operator=(const JobTable&) = delete;
  ~JobTable() { stopAll(); }
  /// Cancels every job and waits for its thread; the table is empty after.
  void stopAll() {
    std::map<std::string, std::shared_ptr<J>> jobs;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs.swap(jobs_);
    }
    for (auto& [id, job] : jobs) {
      job->cancel = true;
      if (job->thread.joinable()) job->thread.join();
    }
  }
  void add(const std::shared_ptr<J>& job) {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_[job->id] = job;
  }
  /// The job, or null for an unknown id.
  std::shared_ptr<J> find(const std::string& id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = jobs_.find(id);
    return it == jobs_.end() ? nullptr : it->second;
  }
  /// Whether a job is in one of the running states.
  template <typename Running> bool any(Running&& running) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, job] : jobs_)
      if (running(job->state())) return true;
    return false;
  }
  /// The finished job's file and its name in a download; empty for an unknown id or a job that is
  /// not done.
  std::pair<std::string, std::string> finishedFile(const std::string& id) const {
    const std::shared_ptr<J> job = find(id);
    if (!job || job->state() != "done") return {};
    return {job->path, job->name};
  }
  /// Asks the job to stop; false for an unknown id.
  bool cancel(const std::string& id) {
    const std::shared_ptr<J> job = find(id);
    if (job) job->cancel = true;
    return job != nullptr;
  }

private:
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<J>> jobs_;
};

} // namespace exa::view
