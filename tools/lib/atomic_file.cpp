#include "tools/lib/atomic_file.hpp"

#include <cstdio>
#include <stdexcept>

#include <unistd.h>

namespace palpable::tools {

AtomicFile::AtomicFile(std::string path)
    : path_(std::move(path)), temp_path_(path_ + ".tmp-" + std::to_string(::getpid())) {
  out_.open(temp_path_, std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error(path_ + ": cannot open for writing");
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::remove(temp_path_.c_str());
  }
}

void AtomicFile::commit() {
  out_.flush();
  if (!out_) throw std::runtime_error(path_ + ": write failed");
  out_.close();
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": cannot rename the finished file into place");
  }
  committed_ = true;
}

}  // namespace palpable::tools
