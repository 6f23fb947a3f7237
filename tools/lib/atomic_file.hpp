#pragma once
// Output files never destroy and never stay partial:
// - a regular file (or a path that does not exist yet) is written into a temporary file beside it
//   and renamed over it only on commit(); a run that fails, throws or is interrupted by SIGINT,
//   SIGTERM, SIGHUP or SIGPIPE leaves no temporary and no partial file behind;
// - a symbolic link is followed: its target is written (atomically, if a regular file) and the
//   link stays a link;
// - a device, FIFO or socket (/dev/null, a pipe), "-" and /dev/stdout (standard output, whatever
//   it is: a pipe, a terminal or a file the shell opened) are written straight through, streaming.
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

namespace palpable::tools {

class AtomicFile {
 public:
  // Throws std::runtime_error naming the path when it cannot be opened.
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary file unless committed

  std::ostream& stream() { return *target_; }
  const std::string& path() const { return path_; }
  // Flushes and closes, throwing on any I/O error; renames nothing yet. A run with several
  // outputs finishes them all before committing any, so that a failure of one (a full disk, a
  // device that refuses the data) leaves none in place.
  void finish();
  // finish(), then renames over the target (atomic mode).
  void commit();
  // True when writing straight through (device, FIFO, socket, standard output).
  bool streaming() const { return temp_path_.empty(); }

 private:
  std::string path_;        // as given
  std::string final_path_;  // where the data ends up (a symlink's target)
  std::string temp_path_;   // empty when streaming
  std::ofstream out_;
  std::ostream* target_ = &out_;
  bool finished_ = false;
  bool committed_ = false;
  int slot_ = -1;  // in the signal handler's table of live temporaries
};

// The descriptor an output path names: 1 for "-" and /dev/stdout, N for /dev/fd/N and
// /proc/self/fd/N, also through symbolic links to them; -1 for any other path. Such a path is the
// descriptor the process was given (a pipe, a terminal, a file opened by the shell, perhaps with
// >>): written through, never resolved to a file and renamed over.
int names_descriptor(const std::string& path);

// True when AtomicFile(path) would write straight through: a descriptor (above), or a path that is
// (or links to) a device, FIFO or socket.
bool writes_through(const std::string& path);

// Installs handlers for SIGINT, SIGTERM, SIGHUP and SIGPIPE (a reader of standard output gone)
// that remove every live temporary file of an AtomicFile and exit with 128 + the signal number
// (the shell's convention: 130 for SIGINT, 141 for SIGPIPE).
void install_output_cleanup_on_signals();

// Throws InputError when two of the given outputs (option name, path) are the same file: a
// device may be named twice (/dev/null), a file may not (the outputs would interleave).
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs);

}  // namespace palpable::tools
