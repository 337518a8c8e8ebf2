#include "lua/file_watcher.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <set>

#if defined(__linux__)
#include <sys/inotify.h>
#include <unistd.h>
#endif

namespace alloy::lua {

namespace fs = std::filesystem;

namespace {
double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
fs::path normal(const fs::path& p) {
  std::error_code ec;
  return fs::absolute(p, ec).lexically_normal();
}
}  // namespace

FileWatcher::FileWatcher(Mode mode, double poll_interval) : interval_(poll_interval) {
#if defined(__linux__)
  if (mode == Mode::Auto) fd_ = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
#else
  (void)mode;
#endif
}

FileWatcher::~FileWatcher() {
#if defined(__linux__)
  if (fd_ >= 0) close(fd_);
#endif
}

void FileWatcher::watch_tree(const fs::path& folder) {
#if defined(__linux__)
  const int wd = inotify_add_watch(
      fd_, folder.c_str(), IN_CLOSE_WRITE | IN_MOVED_TO | IN_MOVED_FROM | IN_CREATE | IN_DELETE);
  if (wd >= 0) watches_[wd] = folder;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec))
    if (e.is_directory(ec)) watch_tree(normal(e.path()));
#else
  (void)folder;
#endif
}

void FileWatcher::add(const fs::path& folder) {
  const fs::path root = normal(folder);
  if (std::find(roots_.begin(), roots_.end(), root) != roots_.end()) return;
  roots_.push_back(root);
  if (fd_ >= 0)
    watch_tree(root);
  else
    stamps_ = scan();
}

std::map<fs::path, FileWatcher::Stamp> FileWatcher::scan() const {
  std::map<fs::path, Stamp> out;
  for (const auto& root : roots_) {
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(root, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (!it->is_regular_file(ec)) continue;
      Stamp s;
      s.time = it->last_write_time(ec);
      s.size = it->file_size(ec);
      out[normal(it->path())] = s;
    }
  }
  return out;
}

std::vector<fs::path> FileWatcher::changed() {
  std::set<fs::path> out;
#if defined(__linux__)
  if (fd_ >= 0) {
    alignas(inotify_event) char buf[16384];
    for (;;) {
      const ssize_t n = read(fd_, buf, sizeof buf);
      if (n <= 0) break;  // EAGAIN: nothing more for now
      for (ssize_t i = 0; i < n;) {
        const auto* e = reinterpret_cast<const inotify_event*>(buf + i);
        auto it = watches_.find(e->wd);
        if (it != watches_.end() && e->len > 0) {
          const fs::path p = it->second / e->name;
          std::error_code ec;
          if ((e->mask & IN_CREATE) && (e->mask & IN_ISDIR))
            watch_tree(p);
          else if (!(e->mask & IN_ISDIR) && !((e->mask & IN_CREATE) && fs::file_size(p, ec) == 0))
            out.insert(p);  // a file created empty is reported when it is written
        }
        i += ssize_t(sizeof(inotify_event) + e->len);
      }
    }
    return {out.begin(), out.end()};
  }
#endif
  const double now = wall_seconds();
  if (now - last_scan_ < interval_) return {};
  last_scan_ = now;
  auto fresh = scan();
  for (const auto& [p, s] : fresh)
    if (auto it = stamps_.find(p); it == stamps_.end() || !(it->second == s)) out.insert(p);
  for (const auto& [p, s] : stamps_)
    if (!fresh.count(p)) out.insert(p);
  stamps_ = std::move(fresh);
  return {out.begin(), out.end()};
}

}  // namespace alloy::lua
