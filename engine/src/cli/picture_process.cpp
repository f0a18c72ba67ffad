#include "cli/picture_process.hpp"

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "cli/python_path.hpp"

extern char** environ;

namespace dem {

bool PictureProcess::start(const std::string& out, bool quiet, std::string& error) {
  const std::string path = comparison_python_path(error);
  if (path.empty()) return false;
  int fds[2];
  if (pipe(fds) != 0) {
    error = std::string("cannot make a pipe: ") + std::strerror(errno);
    return false;
  }
  // Its environment: this one, dem's Python package on PYTHONPATH, and glibc's malloc on transparent
  // huge pages unless the caller set its own tunables (a fresh 4 kB page costs this process's
  // first touch of its pictures' memory some 0.1 s CPU in all; benchmarks/README.md, "The
  // paper's job").
  std::vector<std::string> env;
  env.push_back("PYTHONPATH=" + path);
  if (!std::getenv("GLIBC_TUNABLES")) env.push_back("GLIBC_TUNABLES=glibc.malloc.hugetlb=1");
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "PYTHONPATH=", 11) != 0) env.push_back(*e);
  std::vector<char*> envp;
  for (std::string& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::vector<const char*> args = {DEM_PYTHON_EXE, "-m", "dem.compare.figures", "run", out.c_str(), "--wait"};
  if (quiet) args.push_back("--quiet");
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  // Its own process group: a Ctrl-C at the terminal stops the run (which then tells it not to
  // draw), not Python in the middle of its imports with a traceback.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  const int rc = posix_spawn(&pid_, DEM_PYTHON_EXE, &actions, &attr, const_cast<char* const*>(args.data()),
                             envp.data());
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[0]);
  if (rc != 0) {
    close(fds[1]);
    pid_ = -1;
    error = std::string("cannot start ") + DEM_PYTHON_EXE + ": " + std::strerror(rc);
    return false;
  }
  to_child_ = fds[1];
  return true;
}

int PictureProcess::finish(const char* line) {
  if (pid_ < 0) return 0;
  // A child that has already ended (an import that failed) has closed its stdin: the write then
  // fails with EPIPE instead of raising SIGPIPE here.
  struct sigaction ignore{}, old{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &old);
  const ssize_t n = write(to_child_, line, std::strlen(line));
  (void)n;  // its exit status says what happened
  sigaction(SIGPIPE, &old, nullptr);
  close(to_child_);
  to_child_ = -1;
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int PictureProcess::draw() { return finish("draw\n"); }

void PictureProcess::cancel() { finish("stop\n"); }

}  // namespace dem
