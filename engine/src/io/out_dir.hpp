// A fresh output folder: a run (not a resume) first removes the files an earlier run left there,
// so that no file of another run is read as this run's (docs/outputs.md, "The output folder").
#pragma once

#include <string>

namespace dem {

// Removes from dir the files the engine writes (and their NAME.tmp), the snapshots it wrote into
// dir/snapshots, and the pictures dem.compare.figures draws from them; other files stay. Returns the
// number of files removed.
int clear_run_outputs(const std::string& dir);

}  // namespace dem
