#include "run/thread_choice.hpp"

#include <algorithm>

#include "physics/world.hpp"

namespace dem {

double ThreadChoice::mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

void ThreadChoice::start(World& w, bool enabled) {
  asked_ = w.threads;
  enabled_ = enabled && asked_ > 1;
  w.threads_allowed = 0;  // the scene's count, until a probe says otherwise
  builds_ = w.neighbors.rebuilds;
  if (enabled_) begin_probe(w);
}

double ThreadChoice::mean_but_largest(const std::vector<double>& v) {
  double s = 0, largest = 0;
  for (double x : v) {
    s += x;
    largest = std::max(largest, x);
  }
  return (s - largest) / static_cast<double>(v.size() - 1);
}

double ThreadChoice::close_window() {
  const double m = mean(window_);
  window_steps_ = static_cast<int>(window_.size());
  window_.clear();
  window_s_ = 0;
  return m;
}

void ThreadChoice::begin_probe(World& w) {
  state_ = State::settle_one;
  window_.clear();
  window_s_ = 0;
  probe_s_ = 0;
  slow_ = 0;
  slow_s_ = 0;
  w.threads_allowed = 1;
}

void ThreadChoice::decide(World& w) {
  ++probes;
  const bool many = probe_many_ < kGain * probe_one_;
  hold_ = probes > 1 && many == many_ ? std::min(2 * hold_, kHoldMax) : kHoldFirst;
  many_ = many;
  w.threads_allowed = many ? asked_ : 1;
  held_ = 0;
  recent_.clear();
  recent_at_ = 0;
  state_ = State::hold;
}

void ThreadChoice::after_step(World& w, double seconds) {
  const int n = static_cast<int>(w.discs.size());
  ++steps_at[w.threads_for(n) > 1 ? 1 : 0];
  if (!enabled_) return;
  const double per_disc = seconds / std::max(n, 1);  // a discharge loses discs as it goes
  const bool built = w.neighbors.rebuilds != builds_;
  const bool unlike = built && !built_;  // a list build after a step without one (thread_choice.hpp)
  builds_ = w.neighbors.rebuilds;
  built_ = built;
  if (state_ == State::hold) {
    held_ += seconds;
    if (many_ && !unlike) {  // the last steps, as many as the probe's window of threads, against its mean
      const std::size_t size = static_cast<std::size_t>(std::max(window_steps_, kWindow));
      if (recent_.size() < size) recent_.push_back(per_disc);
      else recent_[recent_at_++ % size] = per_disc;
      if (recent_.size() == size && mean_but_largest(recent_) > kSlower * probe_many_) return begin_probe(w);
    }
    if (held_ >= std::max(hold_, kHoldProbes * probe_s_)) begin_probe(w);
    return;
  }
  probe_s_ += seconds;
  if (unlike && (state_ == State::one || state_ == State::many)) return;
  window_s_ += seconds;
  switch (state_) {
    case State::settle_one: state_ = State::one; window_s_ = 0; return;
    case State::one:
      window_.push_back(per_disc);
      if (!window_full()) return;
      probe_one_ = close_window();
      state_ = State::settle_many;
      w.threads_allowed = asked_;
      return;
    case State::settle_many:
    case State::many: {
      // kAbandon steps in a row, and kWindowSeconds, at kSlowStep times one thread's: the threads
      // lose (a busy neighbour makes their steps several times one thread's); the window stops
      // there. Not two short steps alone: one time slice taken from a thread by another process
      // (milliseconds) makes a step or two of a small scene slow, and the machine keeps that core.
      const bool slow = per_disc > kSlowStep * probe_one_;
      slow_ = slow ? slow_ + 1 : 0;
      slow_s_ = slow ? slow_s_ + seconds : 0;
      if (slow_ >= kAbandon && slow_s_ >= kWindowSeconds) {
        window_.clear();
        window_s_ = 0;
        probe_many_ = slow_s_ / slow_ / std::max(n, 1);  // the slow run's mean
        return decide(w);
      }
      if (state_ == State::settle_many) {
        state_ = State::many;
        window_s_ = 0;
        return;
      }
      window_.push_back(per_disc);
      if (!window_full()) return;
      probe_many_ = close_window();
      return decide(w);
    }
    case State::hold: return;
  }
}

}  // namespace dem
