#include "tools/lib/atomic_file.hpp"

#include "core/check.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <sys/stat.h>
#include <unistd.h>

namespace palpable::tools {
namespace {

// Live temporary files, for the signal handler: fixed buffers, no allocation in the handler.
constexpr int kMaxTemps = 64;
constexpr std::size_t kMaxPath = 4096;
char g_temps[kMaxTemps][kMaxPath];
volatile std::sig_atomic_t g_live[kMaxTemps];

int register_temp(const std::string& path) {
  if (path.size() >= kMaxPath) return -1;
  for (int i = 0; i < kMaxTemps; ++i) {
    if (!g_live[i]) {
      std::memcpy(g_temps[i], path.c_str(), path.size() + 1);
      // The handler must see the whole path before it sees the slot live.
      std::atomic_signal_fence(std::memory_order_seq_cst);
      g_live[i] = 1;
      return i;
    }
  }
  return -1;
}

void unregister_temp(int slot) {
  if (slot >= 0) g_live[slot] = 0;
}

extern "C" void remove_temps_and_exit(int signo) {
  for (int i = 0; i < kMaxTemps; ++i) {
    if (g_live[i]) ::unlink(g_temps[i]);
  }
  ::_exit(128 + signo);
}

bool is_special(const struct stat& st) {
  return S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) || S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode);
}

// N when `path` ends in "/dev/fd/N", "/proc/self/fd/N" or "/proc/PID/fd/N" (this process).
int descriptor_link(const std::string& path) {
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const std::string& prefix : {std::string("/dev/fd/"), std::string("/proc/self/fd/"),
                                    "/proc/" + std::to_string(::getpid()) + "/fd/"}) {
    if (path.size() <= prefix.size() || path.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = path.substr(prefix.size());
    if (digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
    return std::stoi(digits);
  }
  return -1;
}

}  // namespace

int names_descriptor(const std::string& path) {
  if (path == "-") return 1;
  // Follow the links one at a time, stopping at a descriptor link: resolving that one as well
  // gives "pipe:[1234]" (no path) or the file the shell opened, which a rename would replace.
  std::filesystem::path p = path;
  for (int hop = 0; hop < 40; ++hop) {
    const int fd = descriptor_link(p.lexically_normal().string());
    if (fd >= 0) return fd;
    std::error_code ec;
    if (!std::filesystem::is_symlink(std::filesystem::symlink_status(p, ec)) || ec) return -1;
    const std::filesystem::path target = std::filesystem::read_symlink(p, ec);
    if (ec) return -1;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return -1;
}

bool writes_through(const std::string& path) {
  if (names_descriptor(path) >= 0) return true;
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && is_special(st);
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), final_path_(path_) {
  const int fd = names_descriptor(path_);
  if (fd == 1) {  // "-", /dev/stdout or a link to it: standard output, in order with the rest
    target_ = &std::cout;
    std::cout.precision(17);
    return;
  }
  if (fd >= 0) {
    // Another descriptor (/dev/stderr, /dev/fd/3): straight through, appended, never truncated
    // or replaced - it may be a file the shell opened with >>.
    out_.open(path_, std::ios::out | std::ios::app);
    if (!out_) {
      throw InputError(path_, std::string("cannot open for writing: ") + std::strerror(errno));
    }
    out_.precision(17);
    return;
  }
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    // Follow the link: the data goes to its target, the link stays.
    std::error_code ec;
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(path_, ec);
    if (ec) throw InputError(path_, "cannot resolve the symbolic link");
    final_path_ = resolved.string();
  }
  // An output that cannot be opened is a bad argument, found before anything runs (exit 2).
  auto cannot_open = [this](int error) {
    return InputError(path_, std::string("cannot open for writing: ") + std::strerror(error));
  };
  if (::stat(final_path_.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    throw InputError(path_, "is a directory, not a file to write");
  }
  if (::stat(final_path_.c_str(), &st) == 0 && is_special(st)) {
    out_.open(final_path_, std::ios::out);  // straight through, no truncation games
    if (!out_) throw cannot_open(errno);
    out_.precision(17);
    return;
  }
  temp_path_ = final_path_ + ".tmp-" + std::to_string(::getpid());
  out_.open(temp_path_, std::ios::out | std::ios::trunc);
  if (!out_) throw cannot_open(errno);
  slot_ = register_temp(temp_path_);
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_ && !temp_path_.empty()) {
    out_.close();
    std::remove(temp_path_.c_str());
  }
  unregister_temp(slot_);
}

void AtomicFile::finish() {
  if (finished_) return;
  target_->flush();
  if (!*target_) throw std::runtime_error(path_ + ": write failed");
  if (out_.is_open()) out_.close();
  if (!out_) throw std::runtime_error(path_ + ": write failed");
  finished_ = true;
}

void AtomicFile::commit() {
  finish();
  if (temp_path_.empty()) {
    committed_ = true;
    return;
  }
  if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": cannot rename the finished file into place");
  }
  committed_ = true;
  unregister_temp(slot_);
  slot_ = -1;
}

void install_output_cleanup_on_signals() {
  struct sigaction action {};
  action.sa_handler = remove_temps_and_exit;
  sigemptyset(&action.sa_mask);
  // SIGPIPE too: `palpable run ... --trace - --events e.csv | head -1` was killed by it with
  // e.csv.tmp-PID left behind.
  for (int signo : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::sigaction(signo, &action, nullptr);
}

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    for (std::size_t j = i + 1; j < outputs.size(); ++j) {
      const std::string& a = outputs[i].second;
      const std::string& b = outputs[j].second;
      if (a.empty() || b.empty()) continue;
      std::error_code ec1, ec2;
      const auto ca = std::filesystem::weakly_canonical(a, ec1);
      const auto cb = std::filesystem::weakly_canonical(b, ec2);
      const int fd_a = names_descriptor(a);
      const bool same =
          a == b || (fd_a >= 0 && fd_a == names_descriptor(b)) || (!ec1 && !ec2 && ca == cb);
      if (!same) continue;
      struct stat st {};
      // /dev/null twice is fine; one descriptor ("-", /dev/stdout) twice would interleave.
      if (fd_a < 0 && ::stat(a.c_str(), &st) == 0 && is_special(st)) continue;
      throw InputError(outputs[i].first + " and " + outputs[j].first,
                       "both name \"" + a + "\": give each output its own file");
    }
  }
}

}  // namespace palpable::tools
