// `dem run --pictures`: the run's pictures drawn by dem.compare.figures (matplotlib) in a process
// started with the run, so that Python and its imports (numpy, matplotlib) are done while the
// engine steps, and the pictures follow the outputs at once.
#pragma once

#include <string>
#include <sys/types.h>

namespace dem {

class PictureProcess {
 public:
  PictureProcess() = default;
  PictureProcess(const PictureProcess&) = delete;
  PictureProcess& operator=(const PictureProcess&) = delete;
  ~PictureProcess() { cancel(); }
  // Starts `python3 -m dem.compare.figures run DIR --wait [--quiet]`, dem's package on its
  // PYTHONPATH; it imports, then waits for a line on its stdin. False with `error` set when it
  // cannot be started.
  bool start(const std::string& out, bool quiet, std::string& error);
  // The run's outputs are written: tells it to draw and waits for it. Its exit status (0: the
  // pictures are written), or -1 when it ended on a signal.
  int draw();
  // The run did not end well: tells it not to draw (it exits) and waits for it.
  void cancel();

 private:
  pid_t pid_ = -1;
  int to_child_ = -1;  // the write end of its stdin
  int finish(const char* line);
};

}  // namespace dem
