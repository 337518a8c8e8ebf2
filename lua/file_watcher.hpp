// Notices changed files under a few folders, for hot reload: inotify where
// the system has it, else a scan of modification times and sizes every
// `poll_interval` seconds. Never blocks; asked between steps.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace alloy::lua {

class FileWatcher {
 public:
  enum class Mode { Auto, Polling };
  explicit FileWatcher(Mode mode = Mode::Auto, double poll_interval = 0.25);
  ~FileWatcher();
  FileWatcher(const FileWatcher&) = delete;
  FileWatcher& operator=(const FileWatcher&) = delete;

  /// Watches `folder` and its subfolders (new subfolders too).
  void add(const std::filesystem::path& folder);
  /// Files created, written, renamed into place or deleted since the last
  /// call, sorted, each once (lexically normal absolute paths).
  std::vector<std::filesystem::path> changed();
  /// True if inotify is in use, false if polling.
  bool inotify() const { return fd_ >= 0; }

 private:
  struct Stamp {
    std::filesystem::file_time_type time;
    std::uintmax_t size = 0;
    friend bool operator==(const Stamp&, const Stamp&) = default;
  };
  void watch_tree(const std::filesystem::path& folder);
  std::map<std::filesystem::path, Stamp> scan() const;

  int fd_ = -1;
  std::map<int, std::filesystem::path> watches_;  // inotify descriptor -> folder
  std::vector<std::filesystem::path> roots_;
  double interval_;
  double last_scan_ = -1e300;
  std::map<std::filesystem::path, Stamp> stamps_;
};

}  // namespace alloy::lua
