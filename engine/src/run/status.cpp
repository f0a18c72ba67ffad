#include "run/status.hpp"

namespace dem {

const char* to_string(Status s) {
  switch (s) {
    case Status::running: return "running";
    case Status::rest: return "rest";
    case Status::end_time: return "end_time";
    case Status::discharged: return "discharged";
    case Status::jammed: return "jammed";
    case Status::emptied: return "emptied";
    case Status::sheared: return "sheared";
    case Status::unstable: return "unstable";
    case Status::interrupted: return "interrupted";
  }
  return "?";
}

}  // namespace dem
