#pragma once
// Output files are written atomically: into a temporary file beside the target, renamed over it
// only on commit(). A run that fails (or throws) leaves no partial file behind.
#include <fstream>
#include <string>

namespace palpable::tools {

class AtomicFile {
 public:
  // Opens "<path>.tmp-<pid>" for writing; throws std::runtime_error naming the path on failure.
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary file unless committed

  std::ostream& stream() { return out_; }
  const std::string& path() const { return path_; }
  // Flushes, closes and renames over the target; throws on any I/O error.
  void commit();

 private:
  std::string path_;
  std::string temp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace palpable::tools
