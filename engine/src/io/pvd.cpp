#include "io/pvd.hpp"

#include "io/files.hpp"

namespace dem {

void PvdIndex::add(double t, long step, const std::string& discs, const std::string& walls, const std::string& contacts) {
  const std::string at = "    <DataSet timestep=\"" + time_text(t) + "\" part=\"";
  entries_ += at + "0\" file=\"" + discs + "\"/>\n";
  entries_ += at + "1\" file=\"" + walls + "\"/>\n";
  entries_ += at + "2\" file=\"" + contacts + "\"/>\n";
  last_step_ = step;
}

void PvdIndex::write(const std::string& path) const {
  write_file_atomic(path, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n" +
                              entries_ + "  </Collection>\n</VTKFile>\n");
}

}  // namespace dem
