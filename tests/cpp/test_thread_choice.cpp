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
