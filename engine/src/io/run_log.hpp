// run.log of an output folder (docs/outputs.md): the run header, the lines between phases,
// warnings and the final status line, as the run prints them (also with --quiet).
#pragma once

#include <string>

#include "physics/stability.hpp"
#include "physics/world.hpp"
#include "scene/scene_spec.hpp"

namespace dem {

// The header every run prints: the scene, dt, the units, the derived constants of each pair and
// the time-step bounds, with the warnings they call for. Lines end in '\n'.
std::string run_header(const SceneSpec& spec, const World& w, const StabilityReport& st);

class RunLog {
 public:
  // echo: also print each line (stdout; warnings go to stderr).
  explicit RunLog(bool echo = false) : echo_(echo) {}
  // printf-like; the text may hold several lines.
  void say(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void warn(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void add(const std::string& text, bool to_stderr = false);
  // Into the file only, never printed (the resolved scene, as log.lammps echoes its input).
  void file_only(const std::string& text) { text_ += text; }
  const std::string& text() const { return text_; }
  // Writes DIR/run.log atomically; `append`: after the log already there (a resumed run).
  void write(const std::string& dir, bool append) const;

 private:
  bool echo_;
  std::string text_;
};

}  // namespace dem
