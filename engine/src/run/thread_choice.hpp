// The thread count a run steps with, chosen by measurement (integrator.thread_choice = "auto").
// Every thread count gives the same bits (world.hpp, threads), so the choice changes the speed
// of a run, never its results. libgomp's threads wait at a barrier by spinning some
// milliseconds (GOMP_SPINCOUNT, 300000 unless set): on a quiet machine that makes 2 threads
// 1.6x as fast as one on the settled 100k silo, where waits that sleep soon made them slower
// than one; beside another busy process the spinning thread holds the core its partner needs,
// and 2 threads ran 1.8-2.9x slower than one (benchmarks/README.md, "Threads on a busy
// machine"). So the run measures both now and then and steps with the faster.
#pragma once

#include <array>
#include <vector>

namespace dem {

class World;

class ThreadChoice {
 public:
  // A probe: a window with one thread, then one with the scene's threads (each after one step
  // not counted: the first step after a switch pays for new blocks and cold caches), each of
  // kWindow steps and kWindowSeconds at least, or kWindowFew steps and kWindowLong (the other
  // processes' time slices are milliseconds); the mean step time of each window, per disc. The mean, not the median: beside
  // a process that takes a core in time slices of milliseconds, a window of small steps has many
  // fast ones and a few that wait out a slice, and those few are most of its time (a median
  // chose 2 threads for a 10k-disc scene that ran 1.6x slower with them). The threads' window
  // stops after kAbandon steps in a row (the uncounted one included), and kWindowSeconds of
  // them, that take kSlowStep times one thread's mean: beside a busy process a step of 2 spinning
  // threads takes several times one thread's, and a full window of such large steps would cost
  // a short run more than the choice saves. The scene's threads are kept when they are faster
  // by kGain at least (alike, one thread leaves a core to the machine's other work).
  static constexpr int kWindow = 8;
  static constexpr double kWindowSeconds = 0.01;
  // A window of kWindowLong seconds holds many of the other processes' time slices however few
  // its steps: kWindowFew of them are enough. A large scene's steps are tens of milliseconds (25
  // ms at 1M discs, one thread), and a window of kWindow such steps with one thread cost a run of
  // 120 steps 18 of them at half speed.
  static constexpr int kWindowFew = 3;
  static constexpr double kWindowLong = 0.03;
  static constexpr double kGain = 0.95;
  static constexpr int kAbandon = 2;
  static constexpr double kSlowStep = 2.0;
  // Between probes the choice holds for at least kHoldFirst seconds of stepping and kHoldProbes
  // probes' time; the hold doubles while probes confirm the choice, up to kHoldMax, and starts
  // again from kHoldFirst when one overturns it.
  static constexpr double kHoldFirst = 0.5, kHoldMax = 32.0;  // [s]
  static constexpr int kHoldProbes = 32;
  // Holding the scene's threads, a probe starts at once when the mean of the last steps, as
  // many as the probe's window of threads had (kWindow at least), is kSlower times the probe's
  // (another process took a core). The largest of them is left out of that mean: a process that
  // takes a core slows most steps, and one step unlike the rest (a phase's first step, 60 ms
  // against 8.5 at 1M discs with 2 threads) must not set off a probe.
  static constexpr double kSlower = 1.5;
  // A step that builds the neighbour lists afresh does the work of 4-9 steps (1M discs, 2
  // threads; a discharge builds every 50-90 steps). It enters neither a probe's window, which it
  // would tip to one thread, nor the last steps, whose mean it would take past kSlower: counted,
  // the builds set off 5 probes of one thread in a discharge of 600 steps. Unless the step
  // before it built the lists too: a flow that builds at every step has no other steps to measure.

  // Before the run's first step: whether to choose at all (integrator.thread_choice, more than
  // one thread asked). A probe starts at once: the threads' blocks of a run from rest are set by
  // discs alone until step 64 (World::kRebalanceEvery), which costs 2 threads some of their gain
  // (12.8 against 4.5 ms a step at 1M discs), not all of it.
  void start(World& w, bool enabled);
  // After each step, with its wall time: the thread count of the next steps (World::threads_allowed).
  void after_step(World& w, double seconds);

  bool enabled() const { return enabled_; }
  long probes = 0;                  // probes run
  std::array<long, 2> steps_at{};  // steps with one thread, with the scene's threads

 private:
  enum class State { settle_one, one, settle_many, many, hold };
  bool enabled_ = false;
  int asked_ = 1;                  // the scene's thread count
  State state_ = State::settle_one;
  int slow_ = 0;                    // steps in a row of the threads' window past kSlowStep
  double slow_s_ = 0;               // [s] their time
  std::vector<double> window_;      // per-disc step times of the current window
  double window_s_ = 0;             // [s] its steps' time
  int window_steps_ = 0;            // the steps of the last window closed
  long builds_ = 0;                 // the lists' builds (Neighbors::rebuilds) at the last step
  bool built_ = false;              // the last step built them
  bool window_full() const {
    const std::size_t n = window_.size();
    return (n >= static_cast<std::size_t>(kWindow) && window_s_ >= kWindowSeconds) ||
           (n >= static_cast<std::size_t>(kWindowFew) && window_s_ >= kWindowLong);
  }
  double probe_many_ = 0, probe_one_ = 0;  // the last probe's means [s per disc]
  bool many_ = true;                // holding the scene's threads
  double hold_ = kHoldFirst;        // [s] the current hold
  double held_ = 0;                 // [s] stepped since the hold began
  double probe_s_ = 0;              // [s] the last probe took
  std::vector<double> recent_;      // the last kWindow per-disc step times while holding
  std::size_t recent_at_ = 0;
  static double mean(const std::vector<double>& v);
  static double mean_but_largest(const std::vector<double>& v);  // v of 2 at least
  double close_window();  // the window's mean; the window emptied
  void begin_probe(World& w);
  void decide(World& w);
};

}  // namespace dem
