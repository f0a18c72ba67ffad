// One phase of a run (the fill to rest, the discharge, the shear) as the runner drives it
// (runner.hpp): the runner owns the loop, the guard, the last good state, the stop signal,
// checkpoints, progress and the clock; a phase only says what its steps record, what it measures
// after each, and when it ends.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "run/status.hpp"

namespace dem {

class World;
struct BinaryOut;
struct BinaryIn;

class Phase {
 public:
  virtual ~Phase() = default;
  virtual const char* name() const = 0;
  // Called once in every process that steps the phase (fresh or resumed), before begin.
  virtual void attach(World&) {}
  // A fresh start (not on resume): records the phase's start state and samples it. Returns
  // running, or the status it ends with before any step (`reason` says why when unstable).
  virtual Status begin(World& w, std::string& reason) = 0;
  // Before each step: what the step records (pair forces, increments). `stopping`: a stop was
  // requested, so the run ends on the next step that records its pair forces.
  virtual void before_step(World& w, bool stopping) = 0;
  // After each step the guard passed: the phase's measures, samples and end conditions.
  virtual Status after_step(World& w) = 0;
  // Whether after_step and before_step read the discs' velocities only through World::velocity_now
  // or after World::pay_kick: the run loop may then leave velocity Verlet's closing half kick owed
  // to the next step (World::defer_closing_kick). False: the loop pays it after every step.
  virtual bool pays_own_kick() const { return false; }
  // Once, when the run leaves the phase with `status`: its files and metrics.
  virtual void finish(World& w, Status status) = 0;
  // For the progress line: where the phase is, and the fraction done (for the rate and ETA).
  virtual std::string progress(const World& w) const = 0;
  virtual double fraction(const World& w) const = 0;
  // Before a checkpoint: files the phase streams are flushed to what save() says.
  virtual void flush() {}
  // The phase's own state for checkpoints (the world and the runner's are saved beside it).
  virtual void save(BinaryOut&) const {}
  virtual void load(BinaryIn&) {}
  // The phase's metrics for summary.json (under its name) after finish; null when none.
  virtual nlohmann::ordered_json metrics() const { return nullptr; }
};

}  // namespace dem
