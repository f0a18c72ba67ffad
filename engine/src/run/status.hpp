// How a run, or one of its phases, stands: one list for the fill, the discharge and the shear.
#pragma once

namespace dem {

enum class Status {
  running,      // not ended
  rest,         // fill: at rest (the paper's note 3) with end.stop_at_rest
  end_time,     // fill: end.time reached
  discharged,   // discharge: discharge.time reached
  jammed,       // discharge: nothing left for discharge.jam_time (no keystone removal)
  emptied,      // discharge: every disc left
  sheared,      // shear: shear.max_strain reached
  unstable,     // the guard stopped it (runner.hpp): its last good state is written
  interrupted,  // SIGINT / SIGTERM: outputs and a checkpoint are written
};

// The word summary.json and the CLI print.
const char* to_string(Status s);

}  // namespace dem
