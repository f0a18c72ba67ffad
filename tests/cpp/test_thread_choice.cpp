// The run's thread choice (run/thread_choice.hpp), fed step times made up here: it keeps the
// scene's threads when they are faster, drops to one thread when they are slower, probes again
// when its hold is over, and at once when the threads it holds slow down.
#include <gtest/gtest.h>

#include <functional>

#include "physics/world.hpp"
#include "run/thread_choice.hpp"

using namespace dem;

namespace {

// A world of n discs asking for `threads`: the choice reads its size and its thread count only.
World world_of(int n, int threads) {
  World w;
  for (int i = 0; i < n; ++i) w.discs.add(2.5 * i, 0.0, 1.0, 1.0, 0);
  w.threads = threads;
  return w;
}

// Steps with the made-up time t(threads the step ran with) [s], as the runner does.
void run_steps(World& w, ThreadChoice& c, long steps, const std::function<double(int)>& t) {
  for (long s = 0; s < steps; ++s) {
    const int nt = w.threads_for(static_cast<int>(w.discs.size()));
    ++w.steps;
    c.after_step(w, t(nt));
  }
}

constexpr int kDiscs = 3 * World::kMinDiscsPerThread;  // enough for 2 threads

}  // namespace

TEST(ThreadChoice, KeepsTheThreadsWhenTheyAreFaster) {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 2000, [](int nt) { return nt == 2 ? 0.006 : 0.010; });  // 1.67x
  EXPECT_GE(c.probes, 1);
  EXPECT_EQ(w.threads_for(kDiscs), 2);
  // The probes' one-thread windows are all the steps of one thread: a few per cent.
  EXPECT_LT(c.steps_at[0], 0.05 * 2000) << c.steps_at[0] << " steps of one thread";
}

TEST(ThreadChoice, DropsToOneThreadWhenTheThreadsAreSlower) {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 2000, [](int nt) { return nt == 2 ? 0.020 : 0.010; });  // a busy neighbour: 2x slower
  EXPECT_EQ(w.threads_for(kDiscs), 1);
  // The probes' two-thread windows are all the steps of two threads.
  EXPECT_GT(c.steps_at[0], 0.97 * 2000) << c.steps_at[1] << " steps of two threads";
}

TEST(ThreadChoice, AbandonsASlowWindowOfThreads) {
  // Two threads 5x slower than one (spinning beside a busy neighbour): each probe spends
  // kAbandon steps with them, not a window of kWindow.
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 3000, [](int nt) { return nt == 2 ? 0.050 : 0.010; });
  EXPECT_EQ(w.threads_for(kDiscs), 1);
  ASSERT_GE(c.probes, 2);
  EXPECT_EQ(c.steps_at[1], ThreadChoice::kAbandon * c.probes);
}

TEST(ThreadChoice, KeepsTheThreadsThroughAnotherProcesssTimeSlices) {
  // Two threads 1.7x as fast as one on a small scene (0.1 ms steps), but every 100th step
  // another process takes a thread's core for 4 ms, two steps of 2 ms: too short to abandon a
  // window (kWindowSeconds), and the threads still faster on the whole (0.138 ms a step).
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  long step = 0;
  run_steps(w, c, 100000, [&](int nt) {
    const bool slice = ++step % 100 < 2;
    return nt == 2 ? (slice ? 0.002 : 0.0001) : 0.00017;
  });
  EXPECT_EQ(w.threads_for(kDiscs), 2);
  EXPECT_LT(c.steps_at[0], 0.02 * 100000) << c.steps_at[0] << " steps of one thread";
}

TEST(ThreadChoice, FewLongStallsOutweighManyFastSteps) {
  // Beside a process that takes a thread's core in slices of 3 ms, 9 steps of 10 with two threads
  // take 0.1 ms and the 10th waits out a slice: 0.39 ms a step on the whole against one thread's
  // 0.17. Most steps are fast (a median says two threads); the time says one.
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  long step = 0;
  run_steps(w, c, 20000, [&](int nt) { return nt == 2 ? (++step % 10 == 0 ? 0.003 : 0.0001) : 0.00017; });
  EXPECT_EQ(w.threads_for(kDiscs), 1);
  EXPECT_GT(c.steps_at[0], 0.9 * 20000) << c.steps_at[1] << " steps of two threads";
}

TEST(ThreadChoice, AlikeIsOneThread) {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 500, [](int nt) { return nt == 2 ? 0.0098 : 0.010; });  // 2 % faster: below kGain
  EXPECT_EQ(w.threads_for(kDiscs), 1);
}

TEST(ThreadChoice, ProbesAgainWhenTheThreadsSlowDown) {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 300, [](int nt) { return nt == 2 ? 0.006 : 0.010; });
  ASSERT_EQ(w.threads_for(kDiscs), 2);
  const long probes = c.probes;
  // A neighbour takes a core: two threads now take 0.030 s a step. Far within the hold
  // (0.5 s and more), the last kWindow steps' mean sets off a probe, which drops to one thread.
  run_steps(w, c, 40, [](int nt) { return nt == 2 ? 0.030 : 0.010; });
  EXPECT_EQ(c.probes, probes + 1);
  EXPECT_EQ(w.threads_for(kDiscs), 1);
}

TEST(ThreadChoice, ProbesAgainAfterItsHoldAndReturnsToTheThreads) {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 300, [](int nt) { return nt == 2 ? 0.020 : 0.010; });
  ASSERT_EQ(w.threads_for(kDiscs), 1);
  // The neighbour has gone: the next probe, after the hold (32 probes' time, 8.6 s of these
  // steps), finds two threads faster.
  run_steps(w, c, 1500, [](int nt) { return nt == 2 ? 0.006 : 0.010; });
  EXPECT_EQ(w.threads_for(kDiscs), 2);
}

TEST(ThreadChoice, OffOrOneThreadChoosesNothing) {
  World w = world_of(kDiscs, 2);
  ThreadChoice off;
  off.start(w, false);
  run_steps(w, off, 300, [](int nt) { return nt == 2 ? 0.020 : 0.010; });
  EXPECT_EQ(off.probes, 0);
  EXPECT_EQ(w.threads_for(kDiscs), 2);
  EXPECT_EQ(off.steps_at[1], 300);
  World one = world_of(kDiscs, 1);
  ThreadChoice c;
  c.start(one, true);
  run_steps(one, c, 300, [](int) { return 0.01; });
  EXPECT_FALSE(c.enabled());
  EXPECT_EQ(c.probes, 0);
}

TEST(ThreadChoice, LargeStepsMakeShortProbes) {
  // A million discs: 25 ms a step with one thread, 13 ms with two. A probe's windows close after
  // kWindowFew steps (kWindowLong of them), not kWindow: a run of 120 steps spends 4 of them with
  // one thread (the uncounted settling step and a window of 3), not 9.
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  c.start(w, true);
  run_steps(w, c, 120, [](int nt) { return nt == 2 ? 0.013 : 0.025; });
  EXPECT_EQ(c.probes, 1);
  EXPECT_LE(c.steps_at[0], 4) << "steps of one thread";  // 9 with windows of kWindow steps
  EXPECT_EQ(w.threads_for(kDiscs), 2);
}

namespace {

// Steps as run_steps, where the steps builds(s) says (s counted from 1) build the lists afresh and
// take t(threads, true).
void run_steps_building(World& w, ThreadChoice& c, long steps, const std::function<bool(long)>& builds,
                        const std::function<double(int, bool)>& t) {
  for (long s = 1; s <= steps; ++s) {
    const int nt = w.threads_for(static_cast<int>(w.discs.size()));
    ++w.steps;
    const bool build = builds(s);
    if (build) ++w.neighbors.rebuilds;
    c.after_step(w, t(nt, build));
  }
}

// A million discs discharging (the settled 1M silo of benchmarks/speed.py, 600 steps): 8.5 ms a
// step with two threads, 16 with one; a list build 60 / 100 ms.
double million(int nt, bool build) { return nt == 2 ? (build ? 0.060 : 0.0085) : (build ? 0.100 : 0.016); }

// A choice started on a world of kDiscs asking for two threads.
struct Started {
  World w = world_of(kDiscs, 2);
  ThreadChoice c;
  Started() { c.start(w, true); }
};

}  // namespace

TEST(ThreadChoice, ListBuildsSetOffNoProbe) {
  // A build every 60 steps, 7 times the steps around it: one in the last 8 steps would make their
  // mean 1.75 times the probe's, a probe for nothing at each build (10 in 600 steps). Only the
  // holds' probes: one at the start, one after the hold (32 probes' time, some 3 s).
  Started r;
  run_steps_building(r.w, r.c, 600, [](long s) { return s % 60 == 0; }, million);
  EXPECT_LE(r.c.probes, 2);
  EXPECT_LE(r.c.steps_at[0], 8) << "steps of one thread";
  EXPECT_EQ(r.w.threads_for(kDiscs), 2);
}

TEST(ThreadChoice, AListBuildInTheThreadsWindowKeepsThem) {
  // The first probe: one thread for steps 1-4 (the settling step and a window of 3), threads from
  // step 5 (settling), their window from step 6. A build at step 6 counted in that window would
  // make the threads' mean (60 + 8.5 + 8.5) / 3 = 26 ms against one thread's 16: one thread.
  Started r;
  run_steps_building(r.w, r.c, 40, [](long s) { return s == 6; }, million);
  EXPECT_EQ(r.c.probes, 1);
  EXPECT_EQ(r.w.threads_for(kDiscs), 2);
}

TEST(ThreadChoice, OneStepUnlikeTheRestSetsOffNoProbe) {
  // Holding the threads, one step of 60 ms that built nothing (a phase's first step), then a list
  // build (the phase's new walls): not a neighbour taking a core, which slows most steps
  // (ProbesAgainWhenTheThreadsSlowDown).
  Started r;
  run_steps_building(r.w, r.c, 100, [](long) { return false; }, million);
  ASSERT_EQ(r.c.probes, 1);
  run_steps_building(r.w, r.c, 1, [](long) { return false; }, [](int, bool) { return 0.060; });
  run_steps_building(r.w, r.c, 20, [](long s) { return s == 1; }, million);
  EXPECT_EQ(r.c.probes, 1);
  EXPECT_EQ(r.w.threads_for(kDiscs), 2);
}

TEST(ThreadChoice, BuildsAtEveryStepAreMeasured) {
  // A flow that builds its lists at every step: no other steps to measure, so those count. The
  // probe ends and keeps the faster threads; beside a neighbour that makes them slower, one thread.
  Started r;
  run_steps_building(r.w, r.c, 40, [](long) { return true; }, million);
  EXPECT_EQ(r.c.probes, 1);
  EXPECT_EQ(r.w.threads_for(kDiscs), 2);
  Started busy;
  run_steps_building(busy.w, busy.c, 40, [](long) { return true; },
                     [](int nt, bool) { return nt == 2 ? 0.09 : 0.07; });
  EXPECT_EQ(busy.c.probes, 1);
  EXPECT_EQ(busy.w.threads_for(kDiscs), 1);
}
