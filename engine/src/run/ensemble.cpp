#include "run/ensemble.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "io/files.hpp"
#include "io/out_dir.hpp"
#include "io/outputs.hpp"
#include "io/run_log.hpp"
#include "measures/wall_loads.hpp"
#include "run/scene_run.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"

namespace dem {

using json = nlohmann::ordered_json;

namespace {

struct Member {
  int index = 0;
  std::string status;
  json metrics = json::object();
  bool fill_rest = false;
};

// Mean and standard error of the finite values.
json stats(const std::vector<double>& v) {
  std::vector<double> f;
  for (double x : v)
    if (std::isfinite(x)) f.push_back(x);
  json j = {{"n", f.size()}};
  if (f.empty()) return j;
  double m = 0;
  for (double x : f) m += x;
  m /= f.size();
  double var = 0;
  for (double x : f) var += (x - m) * (x - m);
  const double sd = f.size() > 1 ? std::sqrt(var / (f.size() - 1)) : 0.0;
  j["mean"] = m;
  j["std"] = sd;
  j["stderr"] = sd / std::sqrt(static_cast<double>(f.size()));
  j["min"] = *std::min_element(f.begin(), f.end());
  j["max"] = *std::max_element(f.begin(), f.end());
  return j;
}

double get(const json& m, const char* key) {
  return m.contains(key) && m[key].is_number() ? m[key].get<double>() : NAN;
}

}  // namespace

namespace {

std::string member_name(int k) {
  char name[32];
  std::snprintf(name, sizeof name, "member_%02d", k);
  return name;
}

// Member k's scene: every initial centre moved by a uniform amount in [-perturb, perturb] from
// a generator seeded by (seed, k) alone, so a member run alone is the member of any ensemble.
SceneSpec member_spec(const SceneSpec& spec, const EnsembleOptions& opt, int k) {
  SceneSpec s = spec;
  std::mt19937_64 rng(opt.seed * 1000003ull + static_cast<unsigned long>(k));
  std::uniform_real_distribution<double> u(-opt.perturb, opt.perturb);
  for (DiscInit& d : s.discs) {
    d.x += u(rng);
    d.y += u(rng);
  }
  s.progress = false;
  try {
    check_initial_discs(s);
  } catch (const SceneError& e) {
    throw SceneError(std::string("--perturb ") + std::to_string(opt.perturb) + " makes member " + std::to_string(k) +
                     " invalid: " + e.what());
  }
  return s;
}

// What identifies the ensemble a member belongs to (DIR/member_KK/member.json): merge checks it.
json member_identity(const SceneSpec& spec, const EnsembleOptions& opt, int k) {
  json id = {{"scene", spec.name}, {"file", spec.file}, {"member", k}, {"seed", opt.seed}, {"perturb", opt.perturb},
             {"scheme", to_string(spec.scheme)}, {"dt", spec.dt}, {"units", to_string(spec.units)}};
  if (!spec.sets.empty()) id["set"] = spec.sets;  // members of other --set values are another ensemble
  return id;
}

// Runs member k into dir; a member that cannot run is a failed member ("error: ..."), never the
// end of the others.
Member run_member(const SceneSpec& spec_k, const json& identity, int k, const std::string& dir,
                  const std::vector<std::string>& command) {
  Member m;
  m.index = k;
  try {
    const int cleared = clear_run_outputs(dir);  // a fresh member folder (io/out_dir.hpp)
    std::filesystem::create_directories(dir);
    SceneSpec s = spec_k;
    World w;
    const StabilityReport stab = build_world_releasing_discs(s, w);
    RunLog log;  // DIR/run.log: the header and the outcome, as dem run prints them
    log.add(run_header(s, w, stab));
    log.say("  ensemble member %d\n", k);
    if (cleared > 0) log.say("  removed %d files of an earlier run from %s\n", cleared, dir.c_str());
    SceneRun run(s, w, dir);
    run.log = &log;
    const Status status = run.run(false, false);
    json extra;
    RunSummary summary = run.summary(extra);
    summary.command = command;
    m.fill_rest = summary.rest_reached;
    m.status = to_string(status);
    if (run.discharge && run.discharge->metrics().is_object()) m.metrics = run.discharge->metrics();
    write_outputs(dir, s, w, measure_loads(w, s.profile_bin), summary, stab, &extra);
    run.discard_kept();
    if (status == Status::unstable) log.say("  unstable: %s\n", summary.reason.c_str());
    log.say("  %s at t = %.4f s after %ld steps; fill rest %s; %.3g s wall\n", to_string(status), w.time, w.steps,
            summary.rest_reached ? "reached" : "not reached", summary.wall_seconds);
    log.write(dir, false);
    write_file_atomic(dir + "/member.json", identity.dump(2) + "\n");
  } catch (const std::exception& e) {
    m.status = std::string("error: ") + e.what();
  }
  return m;
}

void print_member(const Member& m) {
  std::printf("  %s: %s, %d out by 1 s, flow %.4g discs/s, %s\n", member_name(m.index).c_str(), m.status.c_str(),
              m.metrics.value("discs_out_at_1s", 0), get(m.metrics, "flow_rate_discs"),
              m.metrics.value("pattern", std::string("-")).c_str());
  std::fflush(stdout);
}

// The statistics of the members (DIR/ensemble.json) and the exit code.
int write_ensemble(const json& identity, int members_wanted, const std::vector<Member>& members,
                   const std::string& out_dir, bool quiet) {
  const EnsembleOptions opt{members_wanted, identity["seed"].get<unsigned long>(), identity["perturb"].get<double>(), 0, {}};
  const char* length = identity.value("units", std::string("cgs")) == "si" ? "m" : "cm";  // of the perturbation
  std::vector<double> flow, flow_mass, out1, pb, pbw, ps, psw, jam_at;
  int jammed = 0, unstable = 0, failed = 0, funnel = 0, piping = 0;
  json list = json::array();
  for (const Member& m : members) {
    unstable += m.status == "unstable";
    // A member that blew up or could not run has no result: it counts in no statistic.
    const bool ok = m.status != "unstable" && m.status.rfind("error", 0) != 0;
    failed += !ok;
    const std::string p = ok ? m.metrics.value("pattern", std::string()) : std::string();
    if (ok) {
      flow.push_back(get(m.metrics, "flow_rate_discs"));
      flow_mass.push_back(get(m.metrics, "flow_rate_mass"));
      out1.push_back(get(m.metrics, "discs_out_at_1s"));
      pb.push_back(get(m.metrics, "peak_ratio_bottom"));
      pbw.push_back(get(m.metrics, "peak_ratio_bottom_windowed"));
      ps.push_back(get(m.metrics, "peak_ratio_side"));
      psw.push_back(get(m.metrics, "peak_ratio_side_windowed"));
      jam_at.push_back(get(m.metrics, "jam_at"));
      jammed += m.status == "jammed" || m.metrics.value("jams", 0) > 0;
      funnel += p == "funnel";
      piping += p == "piping";
    }
    list.push_back({{"member", m.index}, {"status", m.status}, {"fill_rest", m.fill_rest},
                    {"discs_out_at_1s", m.metrics.value("discs_out_at_1s", 0)},
                    {"flow_rate_discs", m.metrics.contains("flow_rate_discs") ? m.metrics["flow_rate_discs"] : json(nullptr)},
                    {"pattern", p}, {"jam_at", m.metrics.contains("jam_at") ? m.metrics["jam_at"] : json(nullptr)}});
  }
  const int valid = opt.members - failed;
  const double M = std::max(1, valid);  // the jam fraction's denominator: members with a result
  json js = {{"scene", identity["scene"]}, {"file", identity["file"]}, {"members", opt.members}, {"seed", opt.seed},
             {"perturb", opt.perturb}, {"scheme", identity["scheme"]}, {"dt", identity["dt"]},
             {"flow_rate_discs", stats(flow)}, {"flow_rate_mass", stats(flow_mass)},
             {"discs_out_at_1s", stats(out1)},
             {"peak_ratio_bottom", stats(pb)}, {"peak_ratio_bottom_windowed", stats(pbw)},
             {"peak_ratio_side", stats(ps)}, {"peak_ratio_side_windowed", stats(psw)},
             {"jam_fraction", {{"value", valid > 0 ? json(jammed / M) : json(nullptr)},
                               {"stderr", valid > 0 ? json(std::sqrt(jammed / M * (1 - jammed / M) / M)) : json(nullptr)},
                               {"jammed", jammed}, {"of", valid}}},
             {"jam_at", stats(jam_at)},
             {"pattern", {{"funnel", funnel}, {"piping", piping}, {"undetermined", valid - funnel - piping}}},
             {"unstable", unstable}, {"failed", failed},
             {"note", "mean and standard error (std / sqrt(n)) over members with a value; members that were unstable "
                      "or could not run (failed) count in no statistic; jam fraction: members that met a jam, of "
                      "those with a result; perturbation: uniform [-perturb, perturb] " + std::string(length) +
                      " on every initial centre"},
             {"runs", list}};
  if (identity.contains("set")) js["set"] = identity["set"];
  write_file_atomic(out_dir + "/ensemble.json", js.dump(2) + "\n");
  if (!quiet) {
    auto show = [&](const char* label, const json& s) {
      if (s.contains("mean"))
        std::printf("  %-28s %10.4g +- %-8.3g (n = %d)\n", label, s["mean"].get<double>(), s["stderr"].get<double>(),
                    s["n"].get<int>());
      else
        std::printf("  %-28s %10s\n", label, "-");
    };
    std::printf("ensemble %s: %d members, seed %lu, perturb %g %s\n", identity["scene"].get<std::string>().c_str(),
                opt.members, opt.seed, opt.perturb, length);
    show("flow rate [discs/s]", js["flow_rate_discs"]);
    show("discs out at 1 s", js["discs_out_at_1s"]);
    show("peak/static bottom", js["peak_ratio_bottom"]);
    show("peak/static bottom (window)", js["peak_ratio_bottom_windowed"]);
    show("peak/static side", js["peak_ratio_side"]);
    show("peak/static side (window)", js["peak_ratio_side_windowed"]);
    std::printf("  %-28s %10.3g +- %-8.3g (of %d members with a result)\n", "jam fraction", jammed / M,
                valid > 0 ? js["jam_fraction"]["stderr"].get<double>() : NAN, valid);
    std::printf("  %-28s funnel %d, piping %d, undetermined %d\n", "pattern", funnel, piping,
                valid - funnel - piping);
    std::printf("  written to %s/ensemble.json\n", out_dir.c_str());
  }
  // A study with no member to read fails: 3 when every member was unstable, 4 when some could not run.
  if (failed == opt.members) {
    std::fprintf(stderr, "dem ensemble: every member failed (%d unstable, %d could not run); see %s/ensemble.json\n",
                 unstable, failed - unstable, out_dir.c_str());
    return unstable == opt.members ? 3 : 4;
  }
  // A member that could not run (a folder or file it could not make) is the study's failure too,
  // said on stderr whatever --quiet: its statistics lack a member the user asked for.
  if (failed > unstable) {
    std::fprintf(stderr, "dem ensemble: %d of %d members could not run; the statistics are of the other %d; see "
                 "%s/ensemble.json\n", failed - unstable, opt.members, valid, out_dir.c_str());
    return 4;
  }
  return 0;
}

}  // namespace

int run_ensemble(const SceneSpec& spec, const EnsembleOptions& opt, const std::string& out_dir, bool quiet) {
  // Every member's scene is checked before anything runs or is written.
  std::vector<SceneSpec> specs;
  for (int k = 0; k < opt.members; ++k) specs.push_back(member_spec(spec, opt, k));
  std::filesystem::create_directories(out_dir);
  std::vector<Member> members(opt.members);
  std::atomic<int> next{0};
  std::mutex print;
  auto work = [&]() {
    for (int k; (k = next++) < opt.members;) {
      members[k] = run_member(specs[k], member_identity(spec, opt, k), k, out_dir + "/" + member_name(k), opt.command);
      if (!quiet) {
        std::lock_guard<std::mutex> lock(print);
        print_member(members[k]);
      }
    }
  };
  const int jobs = opt.jobs > 0 ? opt.jobs : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 0; t < std::min(jobs, opt.members); ++t) pool.emplace_back(work);
  for (auto& t : pool) t.join();
  json identity = member_identity(spec, opt, 0);
  identity.erase("member");
  return write_ensemble(identity, opt.members, members, out_dir, quiet);
}

int run_member_alone(const SceneSpec& spec, const EnsembleOptions& opt, int k, const std::string& out_dir, bool quiet) {
  const SceneSpec s = member_spec(spec, opt, k);  // checked before anything is written
  std::filesystem::create_directories(out_dir);
  const Member m = run_member(s, member_identity(spec, opt, k), k, out_dir + "/" + member_name(k), opt.command);
  if (!quiet) print_member(m);
  if (m.status == "unstable") return 3;
  return m.status.rfind("error", 0) == 0 ? 4 : 0;
}

std::string prepare_engine_member(const SceneSpec& spec, const EnsembleOptions& opt, int k, const std::string& out_dir,
                                  const std::string& code, double settle) {
  const SceneSpec s = member_spec(spec, opt, k);  // checked before anything is written
  const std::string dir = out_dir + "/" + member_name(k);
  clear_run_outputs(dir);  // an earlier run's summary.json must not pass for this one's
  std::filesystem::create_directories(dir);
  std::string csv = "x,y\n";
  for (const DiscInit& d : s.discs) csv += fmt17(d.x) + "," + fmt17(d.y) + "\n";
  write_file_atomic(dir + "/member_start.csv", csv);
  json id = member_identity(spec, opt, k);
  id["engine"] = code;
  id["settle"] = settle;
  write_file_atomic(dir + "/member.json", id.dump(2) + "\n");
  return dir;
}

int merge_ensemble(const std::string& out_dir, int members_wanted, bool quiet) {
  namespace fs = std::filesystem;
  std::vector<std::pair<int, fs::path>> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out_dir, ec)) {
    const std::string n = e.path().filename().string();
    int k = -1;
    if (e.is_directory() && std::sscanf(n.c_str(), "member_%d", &k) == 1 && k >= 0 && n == member_name(k))
      found.emplace_back(k, e.path());
  }
  if (ec) throw std::runtime_error(out_dir + ": cannot read the folder: " + ec.message());
  std::sort(found.begin(), found.end());
  if (found.empty()) throw std::runtime_error(out_dir + ": no member_KK folders to merge");
  const auto read_json = [](const fs::path& p) {
    std::ifstream in(p);
    if (!in) throw std::runtime_error(p.string() + ": missing (the member did not finish)");
    try {
      return json::parse(in);
    } catch (const json::exception& e) {
      throw std::runtime_error(p.string() + ": not JSON: " + e.what());
    }
  };
  json identity;
  std::vector<Member> members;
  for (const auto& [k, dir] : found) {
    json id = read_json(dir / "member.json");
    if (id.value("member", -1) != k) throw std::runtime_error((dir / "member.json").string() + ": member " +
                                                              id["member"].dump() + " in the folder of member " + std::to_string(k));
    id.erase("member");
    if (identity.is_null()) identity = id;
    else if (id != identity)
      throw std::runtime_error((dir / "member.json").string() + ": another ensemble (" + id.dump() + ", not " +
                               identity.dump() + ")");
    const json s = read_json(dir / "summary.json");
    Member m;
    m.index = k;
    m.status = s.value("status", std::string("?"));
    // null in a reference code's run (dem run --engine: the rest criterion is not evaluated)
    m.fill_rest = s.contains("rest") && s["rest"].is_object() && s["rest"].contains("reached") &&
                  s["rest"]["reached"].is_boolean() && s["rest"]["reached"].get<bool>();
    if (s.contains("discharge") && s["discharge"].is_object()) m.metrics = s["discharge"];
    members.push_back(std::move(m));
  }
  const int wanted = members_wanted > 0 ? members_wanted : static_cast<int>(members.size());
  for (int k = 0; k < wanted; ++k)
    if (k >= static_cast<int>(members.size()) || members[k].index != k)
      throw std::runtime_error(out_dir + "/" + member_name(k) + ": missing (merge needs members 0 to " +
                               std::to_string(wanted - 1) + ")");
  if (static_cast<int>(members.size()) != wanted)
    throw std::runtime_error(out_dir + ": " + std::to_string(members.size()) + " members, --members " + std::to_string(wanted));
  return write_ensemble(identity, wanted, members, out_dir, quiet);
}

}  // namespace dem
