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
  return S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) || S_ISFIFO(st.st_mode) ||
         S_ISSOCK(st.st_mode);
}

}  // namespace

bool writes_through(const std::string& path) {
  if (path == "-") return true;
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && is_special(st);
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), final_path_(path_) {
  if (path_ == "-") {
    target_ = &std::cout;
    std::cout.precision(17);
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

void AtomicFile::commit() {
  target_->flush();
  if (!*target_) throw std::runtime_error(path_ + ": write failed");
  if (temp_path_.empty()) {
    if (out_.is_open()) out_.close();
    committed_ = true;
    return;
  }
  out_.close();
  if (!out_) throw std::runtime_error(path_ + ": write failed");
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
  for (int signo : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(signo, &action, nullptr);
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
      const bool same = a == b || (!ec1 && !ec2 && ca == cb);
      if (!same) continue;
      struct stat st {};
      if (a != "-" && ::stat(a.c_str(), &st) == 0 && is_special(st)) continue;  // /dev/null twice
      throw InputError(outputs[i].first + " and " + outputs[j].first,
                       "both name \"" + a + "\": give each output its own file");
    }
  }
}

}  // namespace palpable::tools
