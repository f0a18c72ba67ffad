"""What a comparison runs: a scene file and its options become a plan (kind, cases, codes).

An *entry* is one scene with its options, from the command line (``dem compare SCENE.toml ...``)
or from one line of a list file (``reference_inputs/agreement/*.list``: a scene path relative to
the list file, then the same options). Nothing in a study is built in Python that a user could
not write as a scene and a line of options.

Kinds (``--kind``, default from the scene):
- ``collision``: one or two discs that meet and part (gravity may be on): every code runs the
  scene as written (its own velocities), measured from the end state (compare/verdict/calibration.py);
- ``static`` (a scene without ``[discharge]``): ``--start frozen`` (default) lets the native
  engine fill the scene with the shared law, zeroes the velocities, and every code rests from that
  same packing for ``--duration``; ``--start scene --members N`` runs every code from the scene's
  own start, each member jittered by ``--perturb`` (independent dynamics, judged statistically);
- ``janssen``: a tall column run as ``static --start scene`` members for the scene's end.time (or
  ``--duration``), its floor lowered by the scene's prescribed translation, the side-wall profiles
  averaged over the members and fitted with Janssen's law (compare/cases/janssen.py);
- ``discharge`` (a scene with ``[discharge]``): members jittered by ``--perturb``, each settles
  for ``--settle`` then the gate opens for the scene's ``discharge.time`` (or ``--duration``).
  ``--start frozen`` (default): the native engine fills the scene once with the shared law for the
  scene's ``end.time`` (velocities zeroed); member k of every code is that packing jittered with
  seed k, settled ``--settle`` s (default 0.2: FROZEN_DISCHARGE_SETTLE) before the opening.
  ``--start scene``: member k is the scene's own start jittered, each code fills it itself.
- ``shear`` (a scene with ``[shear_box]``: paper 2's simple shear box, bonded ``[clusters]`` or
  free discs): members jittered by ``--perturb``, each compressed under the plate to rest (at most
  ``end.time``, or ``--settle``) and sheared to ``shear.max_strain`` (or for ``--duration`` s of
  wall rotation); dt: ``--dt``, else the scene's halved until the shared scheme is stable with
  the clusters (compare/cases/shear.py ``stable_dt``). LIGGGHTS refuses it (compare/cases/shear.py
  ``liggghts_refusal``).

Every code runs the shared law (common.SHARED_VARIANT) and velocity Verlet at the same dt.
Whatever a reference code cannot express is refused before any run (exit 2), naming the scene
field, the code and why: the refusal is the code's own translation refusing the first case.
"""
from __future__ import annotations

import argparse
import copy
import dataclasses
import math
import shlex
from pathlib import Path

import numpy as np

from dem.compare.cases import margins, shear
from dem.compare.cases.common import ROOT, SHARED_VARIANT, Case, CaseError, resolve, scene_material_index

KINDS = ("collision", "static", "janssen", "discharge", "shear")
REFERENCE_CODES = ("liggghts", "yade", "lammps")
# Defaults per profile (a scene's own values win where it has them: dt, discharge.time).
PROFILE_DEFAULTS = {
    "quick": {"members": 4, "static_duration": 0.3, "settle": 1.0},
    "full": {"members": 8, "static_duration": 0.6, "settle": 1.0},
}
# [s] a discharge member's settling from the frozen packing before the opening. A run from a
# packing starts without the fill's tangential springs, so the packing slumps until friction holds
# it again: in user/silo_2400.toml discs move 0.008 cm on average from 0.05 to 0.1 s, 0.0007 cm
# from 0.2 to 0.3 s (the jitter is 0.001 cm); the jitter's own overlaps relax within a few
# contact times (~1e-3 s). Opened during the slump (0.05 s), LIGGGHTS and YADE flowed 3.6 and
# 4.9 % slower than the engine there (8 members, about 2 standard errors); after 0.2 s, 0.8 and
# 1.1 % faster (6 members).
FROZEN_DISCHARGE_SETTLE = 0.2


class PlanError(ValueError):
    """A scene or option the comparison refuses (exit 2); the message names the field and why."""


PERTURB = {"cgs": 1e-3, "si": 1e-5}   # the default jitter, 1e-3 cm, in the scene's length unit


@dataclasses.dataclass
class Options:
    profile: str = "quick"
    kind: str = ""               # "" = from the scene
    start: str = "frozen"        # static, discharge: "frozen" | "scene"
    members: int = 0             # 0 = the profile's default (ensembles)
    dt: float = 0.0              # [s] 0 = the scene's integrator.dt
    duration: float = 0.0        # [s] 0 = static: the profile's; discharge: discharge.time; collision, janssen: end.time
    settle: float = 0.0          # [s] 0 = the profile's (discharge: before the gate opens; frozen: the fill)
    perturb: float | None = None  # [scene length unit] members' uniform jitter of x and y; None: PERTURB
    native_law: str = "shared"   # "shared" | "scene": the native side runs the scene's own law
    timeout: float = 900.0       # [s] per reference run
    jobs: int = 1                # ensemble members run at once (each member's codes one after another)
    resume: bool = False         # reuse finished runs whose translated inputs are unchanged
    codes: tuple = ()            # a list line's --codes: the codes this entry runs (empty: the command's)
    margins: dict = dataclasses.field(default_factory=dict)   # --margin KIND=DELTA overrides (compare/cases/margins.py)
    metrics: tuple = ()          # --metrics: the statistical metric kinds judged (empty: all of the kind's)

    def resolved_members(self) -> int:
        return self.members or PROFILE_DEFAULTS[self.profile]["members"]


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The per-scene options (the command line's and every list line's)."""
    ap.add_argument("--kind", choices=KINDS, default="", help="what to compare (default: discharge when the "
                    "scene has [discharge], shear when it has [shear_box], else static)")
    ap.add_argument("--start", choices=("frozen", "scene"), default="frozen",
                    help="static: every code from the native engine's rested packing (frozen, deterministic) "
                         "or from the scene's own start, as jittered members (scene, statistical); discharge: "
                         "member k of every code from that rested packing jittered with seed k (frozen) or from "
                         "the scene's own start jittered (scene)")
    ap.add_argument("--members", type=int, default=0, help="ensemble members per code (default: quick 4, full 8)")
    ap.add_argument("--dt", type=float, default=0.0, help="time step [s] of every code (default: the scene's)")
    ap.add_argument("--duration", type=float, default=0.0,
                    help="simulated time [s]: static rest after the start (default quick 0.3, full 0.6), "
                         "discharge after the opening (default: discharge.time), collision and janssen (default: end.time)")
    ap.add_argument("--settle", type=float, default=0.0,
                    help="[s] discharge: settling before the opening (default: frozen 0.2, scene 1); "
                         "static frozen: the native fill (default 1)")
    ap.add_argument("--perturb", type=float, default=None,
                    help="members' jitter of x and y, in the scene's length unit (default 1e-3 cm: 1e-5 in an SI scene)")
    ap.add_argument("--margin", action="append", default=[], metavar="KIND=DELTA",
                    help="the margin of agreement of one metric kind (repeatable): " + ", ".join(margins.MARGINS)
                         + " (default: quick 10 %% / full 5 %% for flow rate, discs out and wall loads; docs/compare.md)")
    ap.add_argument("--metrics", default="", metavar="KIND,KIND",
                    help="judge only these statistical metric kinds of the scene (default: all of its kind)")
    ap.add_argument("--native-law", choices=("shared", "scene"), default="shared",
                    help="scene: the native engine runs the scene's own contact law against the references' "
                         "shared law (a failing metric is then attributed to a law option)")


def options_from(ns: argparse.Namespace, base: Options) -> Options:
    o = dataclasses.replace(base)
    for f in ("kind", "start", "members", "dt", "duration", "settle", "perturb"):
        setattr(o, f, getattr(ns, f))
    o.native_law = ns.native_law
    try:
        o.margins = {**base.margins, **margins.parse(ns.margin)}
    except ValueError as e:
        raise PlanError(str(e)) from None
    kinds = tuple(k.strip() for k in ns.metrics.split(",") if k.strip())
    bad = [k for k in kinds if k not in margins.MARGINS]
    if bad:
        raise PlanError(f"--metrics: unknown {', '.join(bad)} (known: {', '.join(margins.MARGINS)})")
    o.metrics = kinds or base.metrics
    if o.perturb is None:
        o.perturb = base.perturb
    for f, lo in (("members", 0), ("dt", 0.0), ("duration", 0.0), ("settle", 0.0), ("perturb", 0.0)):
        if getattr(o, f) is not None and getattr(o, f) < lo:
            raise PlanError(f"--{f}: must be >= {lo}, got {getattr(o, f)!r}")
    if o.members == 1:
        raise PlanError("--members: an ensemble needs at least 2 members per code (a standard error)")
    return o


@dataclasses.dataclass
class Entry:
    scene: Path
    options: Options
    label: str = ""              # the list line, for messages


def read_list(path: Path, base: Options) -> list[Entry]:
    """A list file: one scene a line (relative to the file), then its options; # starts a comment."""
    ap = argparse.ArgumentParser(prog=str(path), add_help=False, exit_on_error=False)
    ap.add_argument("scene")
    ap.add_argument("--codes", default="", help="the codes this line runs (native, always, and any of "
                    "liggghts,yade,lammps): a scene a reference code cannot express names the others; default: the "
                    "command's --codes")
    add_arguments(ap)
    out = []
    for k, line in enumerate(Path(path).read_text().splitlines(), 1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        try:
            ns = ap.parse_args(shlex.split(text))
        except (argparse.ArgumentError, SystemExit) as e:
            raise PlanError(f"{path}:{k}: {e}") from None
        scene = (Path(path).parent / ns.scene).resolve()
        if not scene.exists():
            raise PlanError(f"{path}:{k}: scene {ns.scene} not found")
        o = options_from(ns, base)
        named = tuple(c.strip() for c in ns.codes.split(",") if c.strip())
        bad = [c for c in named if c not in ("native",) + REFERENCE_CODES]
        if bad:
            raise PlanError(f"{path}:{k}: --codes: unknown {bad}")
        o.codes = ("native",) + tuple(c for c in named if c != "native") if named else ()
        out.append(Entry(scene, o, f"{path}:{k}"))
    if not out:
        raise PlanError(f"{path}: no scenes listed")
    return out


# ------------------------------------------------------------------------------------ plans

@dataclasses.dataclass
class Plan:
    entry: Entry
    name: str
    kind: str
    resolved: dict               # dem resolve output (the scene's own law)
    shared: dict                 # the same with the shared law (what every code translates)
    dt: float
    duration: float
    settle: float
    members: int                 # 1 for deterministic kinds

    @property
    def options(self) -> Options:
        return self.entry.options

    @property
    def perturb(self) -> float:
        """The members' jitter in the scene's length unit: --perturb, else 1e-3 cm whatever the units."""
        if self.options.perturb is not None:
            return self.options.perturb
        return PERTURB[self.resolved.get("units", {}).get("system", "cgs")]


def _kind(resolved: dict, o: Options) -> str:
    if o.kind:
        return o.kind
    if "discharge" in resolved:
        return "discharge"
    if "shear_box" in resolved:
        return "shear"
    return "static"


def make_plan(entry: Entry) -> Plan:
    o = entry.options
    try:
        r = resolve(entry.scene)
    except CaseError as e:
        raise PlanError(f"{entry.scene}: {e}") from None
    kind = _kind(r, o)
    if kind == "shear" and not ("shear_box" in r and "shear" in r):
        raise PlanError(f"{entry.scene}: --kind shear: the scene has no [shear_box] with [shear]")
    if kind != "shear" and "shear_box" in r:
        raise PlanError(f"{entry.scene}: [shear_box]: a shear-box scene is compared as --kind shear; "
                        f"--kind {kind} cannot run it")
    if kind != "shear" and "clusters" in r:
        raise PlanError(f"{entry.scene}: [clusters]: bonded clusters are compared in the shear box only "
                        f"(--kind shear); the {kind} comparison translates no bonds")
    if kind in ("collision", "janssen") and len(set(scene_material_index(r).tolist())) > 1:
        raise PlanError(f"{entry.scene}: fill: --kind {kind} judges discs of one material (its reference "
                        f"{'integrates one mass pair' if kind == 'collision' else 'fits one density'}); "
                        "this scene has several disc materials")
    if kind == "discharge" and "discharge" not in r:
        raise PlanError(f"{entry.scene}: --kind discharge: the scene has no [discharge] table")
    if kind != "discharge" and "discharge" in r:
        raise PlanError(f"{entry.scene}: [discharge]: the scene discharges; --kind {kind} cannot run it")
    shared = copy.deepcopy(r)
    shared["contact"] = dict(SHARED_VARIANT)
    shared["integrator"] = dict(r["integrator"], scheme="velocity_verlet")
    dt = o.dt or float(r["integrator"]["dt"])
    prof = PROFILE_DEFAULTS[o.profile]
    settle = o.settle or prof["settle"]
    if kind == "discharge" and o.start == "frozen" and not o.settle:
        settle = FROZEN_DISCHARGE_SETTLE
    if kind == "shear":
        if not o.dt:
            dt = shear.stable_dt(entry.scene, dt)
        if o.duration:      # a shorter (or longer) shear: the walls turn for --duration s
            strain = math.tan(float(r["shear"]["rate"]) * o.duration)
            if not 0 < strain <= 1:
                raise PlanError(f"{entry.scene}: --duration {o.duration!r}: gives the shear strain "
                                f"{strain!r}; shear.max_strain must lie in (0, 1]")
            shared["shear"] = dict(shared["shear"], max_strain=strain)
        if o.settle:        # the compression's longest time (the scene's end.time)
            shared["end"] = dict(shared["end"], time=o.settle)
        r = dict(r, shear=shared["shear"], end=shared["end"])   # --native-law scene: the same run
        settle = float(shared["end"]["time"])
        duration = shear.shear_time(shared)
        members = o.resolved_members()
        return Plan(entry, entry.scene.stem, kind, r, shared, dt, duration, settle, members)
    if kind in ("collision", "janssen"):
        duration = o.duration or float(r["end"]["time"])
    elif kind == "discharge":
        duration = o.duration or float(r["discharge"]["time"])
    else:
        duration = o.duration or prof["static_duration"]
    if kind == "janssen":
        late = [w["name"] for w in r["walls"] if w.get("motion") and float(w["motion"]["until"]) > duration + 1e-12]
        if late:
            raise PlanError(f"{entry.scene}: walls: {', '.join(late)} still move at the run's end ({duration:g} s, "
                            "--duration or end.time): a Janssen member must rest after its floor is lowered")
    members = o.resolved_members() if statistical_kind(kind, o.start) else 1
    name = entry.scene.stem + ("_members" if kind == "static" and o.start == "scene" else "")
    return Plan(entry, name, kind, r, shared, dt, duration, settle, members)


def statistical(plan: Plan) -> bool:
    """Whether the plan is judged by statistical metrics (members, intervals and margins)."""
    return statistical_kind(plan.kind, plan.options.start)


def statistical_kind(kind: str, start: str) -> bool:
    """The discharge, the static members (a static plan from the scene's start), the Janssen
    column and the shear box run members and are judged by statistical metrics."""
    return kind in ("discharge", "janssen", "shear") or (kind == "static" and start == "scene")


def judges_any(plan: Plan, kinds) -> bool:
    """Whether a statistical plan may judge a metric of one of these margin kinds (its --metrics,
    or every metric of its kind when it names none)."""
    return statistical(plan) and (not plan.options.metrics or any(k in plan.options.metrics for k in kinds))


def codes_of(plan: Plan, codes) -> tuple:
    """The codes a plan runs: the command's, narrowed to its list line's --codes when it has them."""
    return tuple(c for c in codes if not plan.options.codes or c in plan.options.codes)


def start_discs(resolved: dict) -> np.ndarray:
    """(n, 6) x, y, r, vx, vy, omega of the scene's start (each disc's material:
    ``common.scene_material_index``, the same order)."""
    d = np.array(resolved["discs"], float)
    v = np.array(resolved.get("velocities", np.zeros((len(d), 3))), float).reshape(-1, 3)
    return np.column_stack([d[:, :3], v])


def jittered(discs: np.ndarray, member: int, perturb: float) -> np.ndarray:
    """Member k: every x and y moved by a uniform amount in [-perturb, perturb] seeded with k.
    Every member is jittered alike, so that the members are independent draws of one start (the
    scene's own start can be a degenerate one: discs stacked in exact columns never buckle)."""
    out = np.array(discs, float, copy=True)
    rng = np.random.default_rng(1000 + member)
    out[:, :2] += rng.uniform(-perturb, perturb, size=(len(out), 2))
    return out


def member_case(plan: Plan, member: int, discs: np.ndarray | None = None, resolved: dict | None = None) -> Case:
    """The case of one member (or the one case of a deterministic kind)."""
    r = resolved if resolved is not None else plan.shared
    if discs is None:
        discs = jittered(start_discs(r), member, plan.perturb)
    suffix = f"_m{member}" if plan.members > 1 else ""
    mats = scene_material_index(r)      # the scene's discs in its order (jittered or rested) ...
    if len(mats) != len(discs):         # ... or others: Case.material_index decides (or refuses)
        mats = None
    if plan.kind == "discharge":
        return Case(name=f"{plan.name}{suffix}", resolved=r, discs=discs, dt=plan.dt, duration=plan.duration,
                    mode="discharge", settle=plan.settle, seed=member, materials=mats)
    if plan.kind == "shear":
        return Case(name=f"{plan.name}{suffix}", resolved=r, discs=discs, dt=plan.dt, duration=plan.duration,
                    mode="shear", settle=plan.settle, seed=member, materials=mats)
    return Case(name=f"{plan.name}{suffix}", resolved=r, discs=discs, dt=plan.dt, duration=plan.duration,
                seed=member, materials=mats)


def default_list(profile: str) -> Path:
    return ROOT / "reference_inputs" / "agreement" / f"{profile}.list"
