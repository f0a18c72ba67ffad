#include "run/discharge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "io/files.hpp"
#include "io/state.hpp"
#include "measures/arch.hpp"
#include "physics/parallel.hpp"

namespace dem {

using json = nlohmann::ordered_json;

namespace {

Digits17 fmt(double v) { return digits17(v); }
json num_or_null(double v) { return finite_or_null(v); }

DischargeFrame make_frame(const SceneSpec& spec, const World& w) {
  DischargeFrame f;
  f.floor = w.geometry.min_y();
  for (const Wall& wl : w.geometry.walls)
    if (wl.name == spec.discharge.gate) {
      f.slit_left = std::min(wl.ax, wl.bx);
      f.slit_right = std::max(wl.ax, wl.bx);
      f.floor = std::min(wl.ay, wl.by);
    }
  f.width = w.geometry.max_x() - w.geometry.min_x();
  f.x_left = w.geometry.min_x();
  f.x_right = w.geometry.max_x();
  f.xc = 0.5 * (f.slit_left + f.slit_right);
  f.top = w.geometry.max_y();
  f.y_out = f.floor - spec.discharge.outlet_depth;
  f.g = std::hypot(w.gx, w.gy);
  return f;
}

void save_load(BinaryOut& o, const WallLoad& L) {
  o.str(L.name); o.str(L.group);
  o.put(L.fx); o.put(L.fy); o.put(L.normal); o.put(L.shear); o.put(L.contacts);
  o.vec(L.bin_normal); o.vec(L.bin_shear); o.vec(L.bin_contacts);
  o.put(L.bin); o.put(L.length);
}

// Field by field: the struct's padding bytes would make a checkpoint's bytes differ run to run.
void save_removals(BinaryOut& o, const std::vector<Removal>& v) {
  o.put<std::uint64_t>(v.size());
  for (const Removal& x : v) {
    o.put(x.t); o.put(x.id); o.put(x.mass); o.put(x.vx); o.put(x.vy); o.put<std::uint8_t>(x.keystone ? 1 : 0);
  }
}

void load_removals(BinaryIn& r, std::vector<Removal>& v) {
  v.resize(r.count(1ull << 32));
  for (Removal& x : v) {
    x.t = r.get<double>(); x.id = r.get<int>(); x.mass = r.get<double>(); x.vx = r.get<double>();
    x.vy = r.get<double>(); x.keystone = r.get<std::uint8_t>() != 0;
  }
}

void load_load(BinaryIn& r, WallLoad& L) {
  L.name = r.str(1 << 20); L.group = r.str(1 << 20);
  L.fx = r.get<double>(); L.fy = r.get<double>(); L.normal = r.get<double>(); L.shear = r.get<double>();
  L.contacts = r.get<int>();
  r.vec(L.bin_normal); r.vec(L.bin_shear); r.vec(L.bin_contacts);
  L.bin = r.get<double>(); L.length = r.get<double>();
}

}  // namespace

void DischargeState::save(BinaryOut& o) const {
  o.put(t_open); o.put(n_initial); o.put(rmean); o.put(fill_top);
  for (double v : surf0) o.put(v);
  at_open.write_to(o);
  o.put<std::uint64_t>(static_walls.size());
  for (const WallLoad& L : static_walls) save_load(o, L);
  o.put(next_s);
  o.put(static_cast<std::int32_t>(status));
  save_removals(o, removals);
  o.put(jam_at); o.put(jams);
  for (double v : sink_time) o.put(v);
  o.put(series_bytes);
  for (const std::ostringstream* s : {&totals, &flow}) o.str(s->str());
  const auto put_peaks = [&](const PeakTracker& p) {
    o.put(p.raw); o.put(p.windowed); o.put(p.acc); o.put(p.count);
    o.vec(p.last);
  };
  o.put<std::uint64_t>(bin_peaks.size());
  for (const auto& wall : bin_peaks) {
    o.put<std::uint64_t>(wall.size());
    for (const auto& bin : wall) put_peaks(bin);
  }
  o.put<std::uint64_t>(total_peaks.size());
  for (const auto& p : total_peaks) put_peaks(p);
  o.vec(sample_t);
  o.put<std::uint64_t>(next_snap);
  o.put(last_removal); o.put(removed_mass); o.put(moved_fraction);
}

void DischargeState::load(BinaryIn& r) {
  t_open = r.get<double>(); n_initial = r.get<int>(); rmean = r.get<double>();
  fill_top = r.get<double>();
  for (double& v : surf0) v = r.get<double>();
  at_open.read_from(r);
  static_walls.resize(r.count(1 << 20));
  for (WallLoad& L : static_walls) load_load(r, L);
  next_s = r.get<long>();
  const auto s = r.get<std::int32_t>();
  if (s < 0 || s > static_cast<std::int32_t>(Status::interrupted)) r.fail("corrupt discharge state (status)");
  status = static_cast<Status>(s);
  if (status == Status::interrupted) status = Status::running;  // it goes on
  load_removals(r, removals);
  jam_at = r.get<double>(); jams = r.get<int>();
  for (double& v : sink_time) v = r.get<double>();
  series_bytes = r.get<std::uint64_t>();
  for (std::ostringstream* s : {&totals, &flow}) {
    s->str(r.str());
    s->seekp(0, std::ios_base::end);  // append after the restored text
  }
  const auto get_peaks = [&](PeakTracker& p) {
    p.raw = r.get<double>(); p.windowed = r.get<double>(); p.acc = r.get<double>();
    p.count = r.get<std::uint64_t>();
    r.vec(p.last);
  };
  bin_peaks.resize(r.count(1 << 20));
  for (auto& wall : bin_peaks) {
    wall.resize(r.count(1 << 24));
    for (auto& bin : wall) get_peaks(bin);
  }
  total_peaks.resize(r.count(1 << 20));
  for (auto& p : total_peaks) get_peaks(p);
  r.vec(sample_t);
  next_snap = r.get<std::uint64_t>();
  last_removal = r.get<double>(); removed_mass = r.get<double>(); moved_fraction = r.get<double>();
  if (static_walls.size() != bin_peaks.size() || static_walls.size() != total_peaks.size())
    r.fail("corrupt discharge state (walls)");
  for (std::size_t k = 0; k < static_walls.size(); ++k)
    if (bin_peaks[k].size() != static_walls[k].bin_normal.size()) r.fail("corrupt discharge state (bins)");
}


DischargePhase::DischargePhase(const SceneSpec& spec, std::string out_dir) : spec_(spec), out_(std::move(out_dir)) {
  series_path_ = out_ + "/wall_series.csv";
  series_tmp_ = series_path_ + ".tmp";
  st.at_open.set_file(out_ + "/opening_positions.bin");  // kept beside the outputs, not in memory
}

std::string DischargePhase::series_file_problem() const {
  if (st.next_s == 0) return "";  // made at the opening
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string& f = fs::exists(series_tmp_, ec) ? series_tmp_ : series_path_;
  const auto size = fs::file_size(f, ec);
  if (ec) return "the wall series so far (" + series_tmp_ + ", or " + series_path_ + " after a stop on a signal) is missing";
  if (size < st.series_bytes)
    return f + " (the wall series so far) has " + std::to_string(size) + " bytes, fewer than the checkpoint's " +
           std::to_string(st.series_bytes);
  return "";
}

void DischargePhase::attach(World& w) {
  const DischargeSpec& ds = spec_.discharge;
  f_ = make_frame(spec_, w);
  steps_total_ = static_cast<long>(std::ceil(ds.time / w.dt - 1e-9));
  sample_every_ = std::max(1L, static_cast<long>(std::llround(ds.series_interval / w.dt)));
  // The moving average of the peak ratios: peak_window in samples.
  win_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(ds.peak_window / (sample_every_ * w.dt))));
  namespace fs = std::filesystem;
  fs::create_directories(out_ + "/snapshots");
  // The wall series file: new at the opening; a resumed run cut back to the checkpoint's length
  // (a run killed after it wrote on), from its temporary name or, after a stop on a signal, from
  // the complete file that stop wrote.
  if (const std::string why = series_file_problem(); !why.empty()) throw std::runtime_error(why);
  if (st.next_s == 0) {
    static const char header[] = "t,wall,bin,s_mid,x_mid,y_mid,depth_mid,normal,shear\n";
    st.series_out.open(series_tmp_, std::ios::binary | std::ios::trunc);
    st.series_out << header;
    st.series_bytes = sizeof header - 1;
  } else {
    std::error_code ec;
    if (!fs::exists(series_tmp_, ec)) fs::rename(series_path_, series_tmp_);
    fs::resize_file(series_tmp_, st.series_bytes);
    st.series_out.open(series_tmp_, std::ios::binary | std::ios::app);
  }
  if (!st.series_out) throw std::runtime_error("cannot write " + series_tmp_);
}

Status DischargePhase::begin(World& w, std::string& reason) {
  double rmean = 0;
  for (std::size_t i = 0; i < w.discs.size(); ++i) rmean += w.discs.r(i);
  st.rmean = rmean / std::max<std::size_t>(1, w.discs.size());
  // The static state: loads and positions at opening.
  std::vector<PointLoad> static_points;
  measure_loads(w, spec_.profile_bin, st.static_walls, static_points);
  st.t_open = w.time;
  st.n_initial = static_cast<int>(w.discs.size());
  st.at_open.keep(w.discs);
  st.fill_top = -1e300;
  for (std::size_t i = 0; i < w.discs.size(); ++i) st.fill_top = std::max(st.fill_top, w.discs.y[i]);
  surfaces(w.discs, f_.x_left, f_.xc, f_.x_right, f_.floor, spec_.discharge.surface_column, st.surf0);
  for (double& v : st.sink_time) v = NAN;
  st.totals << "t,name,normal,shear,fx,fy\n";
  st.flow << "t,discs_in_silo,discs_below,removed,removed_mass,moved_fraction,surface_left,surface_centre,"
             "surface_right,arch_discs,arch_crown_y\n";
  // Per wall and bin: peaks of the normal force (for the ratios).
  st.bin_peaks.assign(st.static_walls.size(), {});
  for (std::size_t k = 0; k < st.static_walls.size(); ++k) st.bin_peaks[k].resize(st.static_walls[k].bin_normal.size());
  st.total_peaks.assign(st.static_walls.size(), {});
  st.next_s = 0;
  st.status = Status::running;
  if (!w.deactivate_wall(spec_.discharge.gate)) {
    reason = "no gate wall \"" + spec_.discharge.gate + "\" to open";
    return Status::unstable;
  }
  // t = 0: the first sample and the snapshots due at the opening.
  sample(w, 0.0);
  snapshots(w, 0.0);
  if (steps_total_ == 0) return st.status = Status::discharged;
  st.next_s = 1;
  return Status::running;
}

void DischargePhase::before_step(World& w, bool stopping) {
  // Record the pair forces of the steps that read them: a sample's (the arch), the last, a
  // snapshot's, and a jam check's (the arch). A step that ends the run early (jam, empty) is a
  // jam check's or has no pairs.
  const DischargeSpec& ds = spec_.discharge;
  const long s = st.next_s;
  const double t_next = w.time + w.dt - st.t_open;
  w.record_pair_forces = s % sample_every_ == 0 || s == steps_total_ || stopping ||
                         t_next - st.last_removal > ds.jam_time ||
                         (st.next_snap < ds.snapshots.size() && ds.snapshots[st.next_snap] <= t_next + 0.5 * w.dt);
}

Status DischargePhase::after_step(World& w) {
  const DischargeSpec& ds = spec_.discharge;
  const long s = st.next_s;
  const double t = w.time - st.t_open;
  // Outlet: discs below y_out leave the computation (the paper's k = -102 region).
  // One read of y per step; the removal list is built only on the steps that remove.
  const long n_now = static_cast<long>(w.discs.size());
  const bool some_out = parallel_any(n_now, w.threads_for(static_cast<int>(n_now)),
                                     [&](long i) { return w.discs.y[i] < f_.y_out; });
  bool any = false;
  dead_.sorted.clear();
  for (std::size_t i = 0; some_out && i < w.discs.size(); ++i)
    if (w.discs.y[i] < f_.y_out) {
      dead_.sorted.push_back(static_cast<int>(i));
      any = true;
      double vx, vy;  // v(t), an owed closing kick included
      w.velocity_now(i, vx, vy);
      st.removals.push_back({t, w.discs.id_at(i), w.discs.mass(i), vx, vy, false});
      st.removed_mass += w.discs.mass(i);
    }
  if (any) {
    // The log's rows of a step in id order (the user's), whatever the arrays' order.
    const auto first = st.removals.end() - static_cast<std::ptrdiff_t>(dead_.sorted.size());
    if (!w.discs.id.empty())
      std::stable_sort(first, st.removals.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
    w.remove_discs(dead_);
    st.last_removal = t;
  }
  if (w.discs.size() == 0) st.status = Status::emptied;
  // Jam: nothing left through the outlet for jam_time while discs remain in the silo.
  if (st.status != Status::emptied && t - st.last_removal > ds.jam_time) {
    bool inside = false;
    for (double y : w.discs.y) inside |= y > f_.floor;
    if (inside) {
      ++st.jams;
      if (st.jam_at < 0) st.jam_at = t;
      const std::vector<int> arch = find_arch(w, f_.slit_left, f_.slit_right, f_.floor);
      if (!ds.remove_keystone) {
        st.status = Status::jammed;
      } else {
        // Note 4: remove the arch's top (crown) disc; without a found arch, the lowest disc over the slit.
        int pick = -1;
        for (int i : arch)
          if (pick < 0 || w.discs.y[i] > w.discs.y[pick]) pick = i;
        if (pick < 0)
          for (std::size_t i = 0; i < w.discs.size(); ++i)
            if (std::abs(w.discs.x[i] - f_.xc) <= 0.5 * (f_.slit_right - f_.slit_left) + w.discs.r(i) &&
                w.discs.y[i] > f_.floor - w.discs.r(i) && (pick < 0 || w.discs.y[i] < w.discs.y[pick]))
              pick = static_cast<int>(i);
        if (pick < 0) {
          st.status = Status::jammed;
        } else {
          double vx, vy;
          w.velocity_now(static_cast<std::size_t>(pick), vx, vy);
          st.removals.push_back({t, w.discs.id_at(pick), w.discs.mass(pick), vx, vy, true});
          dead_.sorted.assign(1, pick);
          w.remove_discs(dead_);
          st.last_removal = t;
        }
      }
    }
  }
  const bool last = s == steps_total_ || st.status != Status::running;
  if (s % sample_every_ == 0 || last) sample(w, t);
  snapshots(w, t);
  if (st.status != Status::running) return st.status;
  if (last) return st.status = Status::discharged;
  st.next_s = s + 1;
  return Status::running;
}

// A sample: wall forces, flow, surface, arch.
void DischargePhase::sample(World& w, double t) {
  const DischargeSpec& ds = spec_.discharge;
  const std::string tt = time_text(on_step_grid(t, w.dt));  // the rows' time, as the user would write it
  std::vector<WallLoad> walls;
  std::vector<PointLoad> points;
  measure_loads(w, spec_.profile_bin, walls, points);
  st.sample_t.push_back(t);
  std::ostringstream series;  // this sample's rows of the wall series
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const WallLoad& L = walls[k];
    const Wall& wl = w.geometry.walls[k];
    st.totals << tt << ',' << L.name << ',' << fmt(L.normal) << ',' << fmt(L.shear) << ',' << fmt(L.fx) << ','
              << fmt(L.fy) << '\n';
    st.total_peaks[k].add(L.normal, win_);
    for (std::size_t b = 0; b < L.bin_normal.size(); ++b) {
      const double mid = std::min(L.length, (b + 0.5) * L.bin);
      const double xm = wl.ax + (wl.bx - wl.ax) * mid / L.length, ym = wl.ay + (wl.by - wl.ay) * mid / L.length;
      st.bin_peaks[k][b].add(L.bin_normal[b], win_);
      series << tt << ',' << L.name << ',' << b << ',' << fmt(mid) << ',' << fmt(xm) << ',' << fmt(ym) << ','
             << fmt(f_.top - ym) << ',' << fmt(L.bin_normal[b]) << ',' << fmt(L.bin_shear[b]) << '\n';
    }
  }
  const std::string rows = series.str();
  st.series_out.write(rows.data(), static_cast<std::streamsize>(rows.size()));
  st.series_bytes += rows.size();
  for (const PointLoad& P : points)
    st.totals << tt << ',' << P.name << ',' << fmt(std::hypot(P.fx, P.fy)) << ",0," << fmt(P.fx) << ','
              << fmt(P.fy) << '\n';
  int inside = 0, below = 0, moved = 0;
  OpeningPositions::Reader open_at(st.at_open);  // in id order (by_id): block by block
  const std::vector<int> by_id = w.discs.by_id();
  for (std::size_t k = 0; k < w.discs.size(); ++k) {
    const std::size_t i = by_id.empty() ? k : static_cast<std::size_t>(by_id[k]);
    (w.discs.y[i] > f_.floor ? inside : below)++;
    double x0, y0;
    open_at.at(w.discs.id_at(i), x0, y0);
    if (std::hypot(w.discs.x[i] - x0, w.discs.y[i] - y0) >= w.discs.r(i)) ++moved;
  }
  const int removed = static_cast<int>(st.removals.size());
  st.moved_fraction = st.n_initial ? double(moved + removed) / st.n_initial : 0.0;
  double sf[3];
  surfaces(w.discs, f_.x_left, f_.xc, f_.x_right, f_.floor, ds.surface_column, sf);
  for (int c = 0; c < 3; ++c)
    if (std::isnan(st.sink_time[c]) && !(sf[c] > st.surf0[c] - st.rmean)) st.sink_time[c] = t;
  const std::vector<int> arch = find_arch(w, f_.slit_left, f_.slit_right, f_.floor);
  double crown = NAN;
  for (int i : arch) crown = std::isnan(crown) ? w.discs.y[i] : std::max(crown, w.discs.y[i]);
  st.flow << tt << ',' << inside << ',' << below << ',' << removed << ',' << fmt(st.removed_mass) << ','
          << fmt(st.moved_fraction) << ',' << fmt(sf[0]) << ',' << fmt(sf[1]) << ',' << fmt(sf[2]) << ','
          << arch.size() << ',';
  if (!std::isnan(crown)) st.flow << fmt(crown);  // no arch: an empty cell
  st.flow << '\n';
}

// Snapshots at the requested times (and at the end): their files and their entries in the
// discharge's own collections through the run's recorder (which checkpoints save).
void DischargePhase::snapshots(World& w, double t) {
  const DischargeSpec& ds = spec_.discharge;
  while (st.next_snap < ds.snapshots.size() && ds.snapshots[st.next_snap] <= t + 0.5 * w.dt) {
    w.pay_kick();  // the snapshot's velocities
    char stem[32];
    std::snprintf(stem, sizeof stem, "%04zu", st.next_snap);
    record->phase_snapshot(w, stem, &st.at_open, "discharge", t);
    ++st.next_snap;
  }
}

void DischargePhase::flush() {
  st.series_out.flush();  // the file holds at least what the checkpoint says
  if (!st.series_out) throw std::runtime_error("cannot write " + series_tmp_);
}

std::string DischargePhase::progress(const World& w) const {
  char buf[120];
  std::snprintf(buf, sizeof buf, "discharge t = %.3f / %.3f s, %zu removed", w.time - st.t_open, spec_.discharge.time,
                st.removals.size());
  return buf;
}

double DischargePhase::fraction(const World&) const {
  return steps_total_ > 0 ? double(st.next_s) / steps_total_ : 1.0;
}

namespace {
// Each wall's ratios of peak to static: the raw maximum and the maximum of a moving average, the
// wall's and its bins'; best_bottom, best_side: the largest bin ratios (raw, windowed) of the
// bottom and side walls, the gate left out.
json wall_peaks(const DischargeState& st, const std::string& gate, double best_bottom[2], double best_side[2]) {
  const std::vector<WallLoad>& static_walls = st.static_walls;
  json walls_json = json::array();
  for (std::size_t k = 0; k < static_walls.size(); ++k) {
    const WallLoad& S = static_walls[k];
    const double raw = st.total_peaks[k].raw, wnd = st.total_peaks[k].windowed;
    json bins = json::array();
    double smax = 0;
    for (double v : S.bin_normal) smax = std::max(smax, v);
    for (std::size_t b = 0; b < S.bin_normal.size(); ++b) {
      const double br = st.bin_peaks[k][b].raw, bw = st.bin_peaks[k][b].windowed;
      // Bins that carried little at rest have no meaningful ratio (one contact of 1 disc weight).
      const bool ok = S.bin_normal[b] >= 0.25 * smax && smax > 0;
      const double rr = ok ? br / S.bin_normal[b] : NAN, rw = ok ? bw / S.bin_normal[b] : NAN;
      bins.push_back({{"bin", b}, {"static", S.bin_normal[b]}, {"peak", br}, {"peak_windowed", bw},
                      {"ratio", num_or_null(rr)}, {"ratio_windowed", num_or_null(rw)}});
      if (ok && S.name != gate) {
        double* best = S.group == "bottom" ? best_bottom : (S.group.rfind("side", 0) == 0 ? best_side : nullptr);
        if (best) {
          best[0] = std::max(best[0], rr);
          best[1] = std::max(best[1], rw);
        }
      }
    }
    walls_json.push_back({{"name", S.name}, {"group", S.group}, {"static_normal", S.normal}, {"peak_normal", raw},
                          {"peak_normal_windowed", wnd},
                          {"ratio", S.normal > 0 ? json(raw / S.normal) : json(nullptr)},
                          {"ratio_windowed", S.normal > 0 ? json(wnd / S.normal) : json(nullptr)}, {"bins", bins}});
  }
  return walls_json;
}

// The flow pattern (docs/outputs.md): where the top surface first sank.
std::string flow_pattern(const double* sink_time) {
  const double t_walls = std::isnan(sink_time[0]) ? sink_time[2]
                         : std::isnan(sink_time[2]) ? sink_time[0] : std::min(sink_time[0], sink_time[2]);
  if (!std::isnan(t_walls) && (std::isnan(sink_time[1]) || t_walls < sink_time[1])) return "funnel";
  if (!std::isnan(sink_time[1]) && (std::isnan(t_walls) || sink_time[1] <= t_walls)) return "piping";
  return "undetermined";
}
}  // namespace

void DischargePhase::finish(World& w, Status status) {
  namespace fs = std::filesystem;
  const DischargeSpec& ds = spec_.discharge;
  st.status = status;
  st.series_out.close();
  if (!st.series_out) throw std::runtime_error("cannot write " + series_tmp_);
  fs::rename(series_tmp_, series_path_);
  write_file_atomic(out_ + "/wall_totals_series.csv", st.totals.str());
  write_file_atomic(out_ + "/flow_series.csv", st.flow.str());
  {
    std::ostringstream o;
    o << "t,id,mass,vx,vy,how\n";
    for (const Removal& r : st.removals)
      o << time_text(on_step_grid(r.t, w.dt)) << ',' << r.id << ',' << fmt(r.mass) << ',' << fmt(r.vx) << ',' << fmt(r.vy) << ','
        << (r.keystone ? "keystone" : "outlet") << '\n';
    write_file_atomic(out_ + "/removals.csv", o.str());
  }
  record->write_collection("discharge", out_);

  double best_bottom[2] = {0, 0}, best_side[2] = {0, 0};
  const json walls_json = wall_peaks(st, ds.gate, best_bottom, best_side);
  const double* sink_time = st.sink_time;
  const std::string pattern = flow_pattern(sink_time);
  const std::vector<Removal>& removals = st.removals;
  int out_1s = 0;
  for (const Removal& r : removals)
    if (!r.keystone && r.t <= 1.0 + 1e-12) ++out_1s;
  const double q = flow_rate(removals);
  const double m_disc = w.discs.size() ? w.discs.mass(0) : (removals.empty() ? 1.0 : removals[0].mass);
  outcome_ = {status, w.time - st.t_open, removals.size(), out_1s, q / m_disc, pattern, best_bottom[0], best_side[0]};
  metrics_ = {
      {"status", to_string(status)},
      {"t_open", on_step_grid(st.t_open, w.dt)},
      {"duration", on_step_grid(w.time - st.t_open, w.dt)},
      {"n_initial", st.n_initial},
      {"removed", removals.size()},
      {"removed_by_hand", std::count_if(removals.begin(), removals.end(), [](const Removal& r) { return r.keystone; })},
      {"discs_out_at_1s", out_1s},
      {"flow_rate_mass", num_or_null(q)},
      {"flow_rate_discs", num_or_null(q / m_disc)},
      {"flow_rate_note", std::string("slope of cumulative removed mass [") +
                             (spec_.units == Units::si ? "kg/s per m" : "g/s per cm") +
                             "] from the 5th removal on (least squares)"},
      {"jammed", status == Status::jammed},
      {"jam_at", st.jam_at >= 0 ? json(on_step_grid(st.jam_at, w.dt)) : json(nullptr)},
      {"jams", st.jams},
      {"peak_ratio_bottom", best_bottom[0]},
      {"peak_ratio_bottom_windowed", best_bottom[1]},
      {"peak_ratio_side", best_side[0]},
      {"peak_ratio_side_windowed", best_side[1]},
      {"ratio_note", "max over the bins (static >= 1/4 of the wall's largest) of peak / static normal force; "
                     "windowed: moving average over peak_window"},
      {"pattern", pattern},
      {"surface_sink_time", {{"left_wall", num_or_null(on_step_grid(sink_time[0], w.dt))},
                             {"centre", num_or_null(on_step_grid(sink_time[1], w.dt))},
                             {"right_wall", num_or_null(on_step_grid(sink_time[2], w.dt))}}},
      {"pattern_note", "funnel: the top surface first sinks (by one mean radius) at a wall column; piping: first at "
                       "the centre column"},
      {"moved_fraction_end", st.moved_fraction},
      {"dead_fraction_end", 1.0 - st.moved_fraction},
      {"gate", ds.gate},
      {"slit", {f_.slit_left, f_.slit_right}},
      {"outlet_y", f_.y_out},
      {"walls", walls_json},
      {"fill_top", st.fill_top},
      {"width", f_.width},
      {"gravity", f_.g}};
}

}  // namespace dem
