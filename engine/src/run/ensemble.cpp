#include "run/ensemble.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>
#include <vector>

#include "io/outputs.hpp"
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

int run_ensemble(const SceneSpec& spec, const EnsembleOptions& opt, const std::string& out_dir, bool quiet) {
  // Every member's scene is checked before anything runs or is written.
  std::vector<SceneSpec> specs(opt.members, spec);
  for (int k = 0; k < opt.members; ++k) {
    std::mt19937_64 rng(opt.seed * 1000003ull + static_cast<unsigned long>(k));
    std::uniform_real_distribution<double> u(-opt.perturb, opt.perturb);
    for (DiscInit& d : specs[k].discs) {
      d.x += u(rng);
      d.y += u(rng);
    }
    specs[k].progress = false;
    try {
      check_initial_discs(specs[k]);
    } catch (const SceneError& e) {
      throw SceneError(std::string("--perturb ") + std::to_string(opt.perturb) + " makes member " + std::to_string(k) +
                       " invalid: " + e.what());
    }
  }
  std::filesystem::create_directories(out_dir);
  std::vector<Member> members(opt.members);
  std::atomic<int> next{0};
  std::mutex print;
  auto work = [&]() {
    for (int k; (k = next++) < opt.members;) {
      char name[32];
      std::snprintf(name, sizeof name, "member_%02d", k);
      const std::string dir = out_dir + "/" + name;
      try {
      std::filesystem::create_directories(dir);
      World w;
      const StabilityReport stab = build_world_releasing_discs(specs[k], w);
      SceneRun run(specs[k], w, dir);
      const Status status = run.run(false, false);
      json extra;
      const RunSummary summary = run.summary(extra);
      Member& m = members[k];
      m.index = k;
      m.fill_rest = summary.rest_reached;
      m.status = to_string(status);
      if (run.discharge && run.discharge->metrics().is_object()) m.metrics = run.discharge->metrics();
      write_outputs(dir, specs[k], w, summary, stab, &extra);
      run.discard_kept();
      } catch (const std::exception& e) {  // one failed member must not take the others down
        members[k].index = k;
        members[k].status = std::string("error: ") + e.what();
      }
      const Member& m = members[k];
      if (!quiet) {
        std::lock_guard<std::mutex> lock(print);
        std::printf("  %s: %s, %d out by 1 s, flow %.4g discs/s, %s\n", name, m.status.c_str(),
                    m.metrics.value("discs_out_at_1s", 0), get(m.metrics, "flow_rate_discs"),
                    m.metrics.value("pattern", std::string("-")).c_str());
        std::fflush(stdout);
      }
    }
  };
  const int jobs = opt.jobs > 0 ? opt.jobs : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 0; t < std::min(jobs, opt.members); ++t) pool.emplace_back(work);
  for (auto& t : pool) t.join();

  std::vector<double> flow, flow_mass, out1, pb, pbw, ps, psw, jam_at;
  int jammed = 0, unstable = 0, failed = 0, funnel = 0, piping = 0;
  json list = json::array();
  for (const Member& m : members) {
    flow.push_back(get(m.metrics, "flow_rate_discs"));
    flow_mass.push_back(get(m.metrics, "flow_rate_mass"));
    out1.push_back(get(m.metrics, "discs_out_at_1s"));
    pb.push_back(get(m.metrics, "peak_ratio_bottom"));
    pbw.push_back(get(m.metrics, "peak_ratio_bottom_windowed"));
    ps.push_back(get(m.metrics, "peak_ratio_side"));
    psw.push_back(get(m.metrics, "peak_ratio_side_windowed"));
    jam_at.push_back(get(m.metrics, "jam_at"));
    jammed += m.status == "jammed" || m.metrics.value("jams", 0) > 0;
    unstable += m.status == "unstable";
    failed += m.status == "unstable" || m.status.rfind("error", 0) == 0;
    const std::string p = m.metrics.value("pattern", std::string());
    funnel += p == "funnel";
    piping += p == "piping";
    list.push_back({{"member", m.index}, {"status", m.status}, {"fill_rest", m.fill_rest},
                    {"discs_out_at_1s", m.metrics.value("discs_out_at_1s", 0)},
                    {"flow_rate_discs", m.metrics.contains("flow_rate_discs") ? m.metrics["flow_rate_discs"] : json(nullptr)},
                    {"pattern", p}, {"jam_at", m.metrics.contains("jam_at") ? m.metrics["jam_at"] : json(nullptr)}});
  }
  const double M = opt.members;
  json js = {{"scene", spec.name}, {"file", spec.file}, {"members", opt.members}, {"seed", opt.seed},
             {"perturb", opt.perturb}, {"scheme", to_string(spec.scheme)}, {"dt", spec.dt},
             {"flow_rate_discs", stats(flow)}, {"flow_rate_mass", stats(flow_mass)},
             {"discs_out_at_1s", stats(out1)},
             {"peak_ratio_bottom", stats(pb)}, {"peak_ratio_bottom_windowed", stats(pbw)},
             {"peak_ratio_side", stats(ps)}, {"peak_ratio_side_windowed", stats(psw)},
             {"jam_fraction", {{"value", jammed / M}, {"stderr", std::sqrt(jammed / M * (1 - jammed / M) / M)},
                               {"jammed", jammed}}},
             {"jam_at", stats(jam_at)},
             {"pattern", {{"funnel", funnel}, {"piping", piping}, {"undetermined", opt.members - funnel - piping}}},
             {"unstable", unstable},
             {"note", "mean and standard error (std / sqrt(n)) over members with a value; jam fraction: members "
                      "that met a jam; perturbation: uniform [-perturb, perturb] cm on every initial centre"},
             {"runs", list}};
  write_file_atomic(out_dir + "/ensemble.json", js.dump(2) + "\n");
  if (!quiet) {
    auto show = [&](const char* label, const json& s) {
      if (s.contains("mean"))
        std::printf("  %-28s %10.4g +- %-8.3g (n = %d)\n", label, s["mean"].get<double>(), s["stderr"].get<double>(),
                    s["n"].get<int>());
      else
        std::printf("  %-28s %10s\n", label, "-");
    };
    std::printf("ensemble %s: %d members, seed %lu, perturb %g cm\n", spec.name.c_str(), opt.members, opt.seed,
                opt.perturb);
    show("flow rate [discs/s]", js["flow_rate_discs"]);
    show("discs out at 1 s", js["discs_out_at_1s"]);
    show("peak/static bottom", js["peak_ratio_bottom"]);
    show("peak/static bottom (window)", js["peak_ratio_bottom_windowed"]);
    show("peak/static side", js["peak_ratio_side"]);
    show("peak/static side (window)", js["peak_ratio_side_windowed"]);
    std::printf("  %-28s %10.3g +- %-8.3g\n", "jam fraction", jammed / M, js["jam_fraction"]["stderr"].get<double>());
    std::printf("  %-28s funnel %d, piping %d, undetermined %d\n", "pattern", funnel, piping,
                opt.members - funnel - piping);
    std::printf("  written to %s/ensemble.json\n", out_dir.c_str());
  }
  // A study with no member to read fails: 3 when every member was unstable, 4 when some could not run.
  if (failed == opt.members) {
    std::fprintf(stderr, "dem ensemble: every member failed (%d unstable, %d could not run); see %s/ensemble.json\n",
                 unstable, failed - unstable, out_dir.c_str());
    return unstable == opt.members ? 3 : 4;
  }
  return 0;
}

}  // namespace dem
