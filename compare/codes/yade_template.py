# YADE 2023.02a script for one comparison case; copied next to yade_case.json by
# compare/codes/yade_backend.py and run there as `yade -n -jN -x yade_script.py` (cwd = the run folder).
# Not importable outside YADE: it uses YADE's globals (O, ViscElMat, PyRunner, ...).
#
# What it does (every number comes from yade_case.json, written by the backend):
# - discs: spheres at z = 0 with blockedDOFs 'zXY', each of its own material, mass rho pi r^2 of
#   that material's rho (per 1 cm), inertia m r^2/2;
# - walls: one facet per wall segment, a triangle whose edge is the segment (z = 0) and whose
#   apex is out of the plane, so the segment's interior gives plane contacts and its ends vertex
#   (point) contacts; a "guard" switches off vertex contacts the engine does not have (an end
#   that is not one of the scene's points, or a point owned by an adjacent wall);
# - law: ViscElMat + Ip2_ViscElMat_ViscElMat_ViscElPhys (series combination, materials from the
#   backend) + Law2_ScGeom_ViscElPhys_Basic, friction per material pair via MatchMaker;
# - NewtonIntegrator(damping=0) (leapfrog), fixed dt, no time stepper;
# - monitor (every sample_every steps, after the forces and before the integrator): wall
#   contact forces (normal + elastic shear + viscous shear as the law applied them);
# - scanner (every scan_every steps, same place): checks (non-finite state, discs outside the
#   container, energy above the initial budget) and the candidate discs of guard and remover;
# - moving walls: a mover (every step, last before the integrator) gives a wall's facet its
#   prescribed velocity during the steps of its window, and NewtonIntegrator moves it;
# - discharge: settle n_settle steps, erase the gate, run n_run steps; a remover erases discs
#   whose centre is below outlet_y and logs the step;
# - final (one step at the end, before the integrator): contacts, discs with velocities
#   synchronised to the force step (leapfrog half step), kinetic energy;
# - snapshots (when snapshot_every > 0): YADE's VTKRecorder (spheres, velocity, id) every
#   snapshot_every steps from the start (static) or the opening (discharge), same place as the
#   monitor, to snapshots/discs_spheres.ITER.vtu (read with meshio by the backend).
# Outputs (full precision, repr): yade_result.json, yade_series.csv (t,wall,px,py,fx,fy,vertex).
import json
import math
import time
import traceback

CASE_FILE = "yade_case.json"
RESULT_FILE = "yade_result.json"
SERIES_FILE = "yade_series.csv"

S = {}   # run state shared by the PyRunner callbacks


def _finite(*vals):
    return all(math.isfinite(v) for v in vals)


def _proj(w, x, y):
    """Projection parameter of (x, y) on wall w (0 at from, 1 at to)."""
    ax, ay, bx, by = w["ax"], w["ay"], w["bx"], w["by"]
    ex, ey = bx - ax, by - ay
    return ((x - ax) * ex + (y - ay) * ey) / (ex * ex + ey * ey)


def _clamped_point(w, x, y):
    u = min(1.0, max(0.0, _proj(w, x, y)))
    return w["ax"] + u * (w["bx"] - w["ax"]), w["ay"] + u * (w["by"] - w["ay"])


def setup():
    C = json.load(open(CASE_FILE))
    S["case"] = C
    S["failed"] = None
    S["dt"] = C["dt"]
    O.reset()
    O.dt = C["dt"]
    disc_mat = {}
    for name, d in sorted(C["disc_materials"].items()):
        disc_mat[name] = O.materials.append(ViscElMat(kn=d["kn"], cn=d["cn"], ks=d["ks"], cs=d["cs"],
                                                      density=d["density"], label="disc_" + name))
    wall_mat = {}
    for name, m in sorted(C["wall_materials"].items()):
        wall_mat[name] = O.materials.append(ViscElMat(kn=m["kn"], cn=m["cn"], ks=m["ks"], cs=m["cs"],
                                                      density=1.0, label="wall_" + name))
    mat_id = dict(disc_mat, **wall_mat)
    matches = [(mat_id[a], mat_id[b], math.atan(mu)) for a, b, mu in C["friction"]]
    ids = sorted(wall_mat.values())
    for a in range(len(ids)):
        for b in range(a, len(ids)):
            matches.append((ids[a], ids[b], 0.0))   # facets never touch each other

    # Walls: one facet each; edge = the segment at z = 0, apex above its midpoint.
    walls = []
    for w in C["walls"]:
        (ax, ay), (bx, by) = w["from"], w["to"]
        length = math.hypot(bx - ax, by - ay)
        apex = (0.5 * (ax + bx), 0.5 * (ay + by), max(0.5 * length, 2.0 * C["rmax"]))
        f = utils.facet([(ax, ay, 0.0), (bx, by, 0.0), apex], material=wall_mat[w["material"]],
                        fixed=True)
        wid = O.bodies.append(f)
        walls.append({"name": w["name"], "id": wid, "ax": ax, "ay": ay, "bx": bx, "by": by,
                      "present": True})
        if w.get("motion"):   # a prescribed translation (the mover)
            m = w["motion"]
            walls[-1]["motion"] = (m["velocity"][0], m["velocity"][1], m["i_from"], m["i_until"], ax, ay, bx, by)
    S["walls"] = walls
    S["wall_by_id"] = {w["id"]: w for w in walls}

    # Discs in the starting order.
    disc_ids, props = [], []
    for k, (x, y, r, vx, vy, om) in enumerate(C["discs"]):
        if not _finite(x, y, r, vx, vy, om) or not r > 0:
            raise _InputError(f"disc {k}: non-finite or non-positive value in x, y, r, vx, vy, omega "
                              f"= {[x, y, r, vx, vy, om]!r}")
        name = C["disc_material_of"][k]
        b = utils.sphere((x, y, 0.0), r, material=disc_mat[name])
        m = C["disc_materials"][name]["density"] * math.pi * r * r
        b.state.mass = m
        b.state.inertia = Vector3(0.5 * m * r * r, 0.5 * m * r * r, 0.5 * m * r * r)
        b.state.blockedDOFs = "zXY"
        b.state.vel = Vector3(vx, vy, 0.0)
        b.state.angVel = Vector3(0.0, 0.0, om)
        disc_ids.append(O.bodies.append(b))
        props.append((m, 0.5 * m * r * r, r))
    S["disc_ids"] = disc_ids
    S["props"] = props
    S["present"] = [True] * len(disc_ids)
    S["removals"] = []          # (step, index, vx, vy)
    S["series_t"] = []
    S["series_rows"] = []
    S["mismatch"] = 0.0
    S["guard_flips"] = 0
    S["guard_steps"] = 0
    S["pairs_seen"] = {}
    S["final"] = None
    g = C["gravity"]
    S["g"] = (g[0], g[1])
    S["i_open"] = C["n_settle"]
    S["i_end"] = C["n_settle"] + C["n_run"]
    S["gate_open"] = False
    S["E0"] = None
    S["ke_max"] = 0.0

    O.engines = [
        PyRunner(command="remover()", iterPeriod=1, dead=True, label="remover_engine"),
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Facet_Aabb()]),
        PyRunner(command="guard()", iterPeriod=1, dead=True, label="guard_engine"),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom()],
                        [Ip2_ViscElMat_ViscElMat_ViscElPhys(frictAngle=MatchMaker(matches=matches))],
                        [Law2_ScGeom_ViscElPhys_Basic()]),
        PyRunner(command="scan()", iterPeriod=C["scan_every"], initRun=True, label="scan_engine"),
        PyRunner(command="monitor()", iterPeriod=C["sample_every"], initRun=True,
                 dead=C["n_settle"] > 0, label="monitor_engine"),
        PyRunner(command="final()", iterPeriod=1, dead=True, label="final_engine"),
    ]
    if C.get("snapshot_every"):
        os.makedirs("snapshots", exist_ok=True)
        O.engines = O.engines + [VTKRecorder(fileName="snapshots/discs_", recorders=["spheres", "velocity", "id"],
                                             iterPeriod=C["snapshot_every"], initRun=True, multiblock=False,
                                             ascii=False, dead=C["n_settle"] > 0, label="snap_engine")]
    if any(w.get("motion") for w in walls):
        O.engines = O.engines + [PyRunner(command="mover()", iterPeriod=1, label="mover_engine")]
    O.engines = O.engines + [NewtonIntegrator(damping=0.0, gravity=(g[0], g[1], 0.0))]
    _update_guarded_ends()


class _InputError(Exception):
    pass


# ---------------------------------------------------------------------------------------------
# Guard: which wall ends may act as vertex (point) contacts.
def _update_guarded_ends():
    """Ends P of present walls where a vertex contact is not always the engine's contact: P is
    not one of the scene's points, or another present wall also ends there."""
    C = S["case"]
    pts = [tuple(p) for p in C["points"]]
    tol = 1e-9
    ends = {}
    for w in S["walls"]:
        if not w["present"]:
            continue
        for (x, y) in ((w["ax"], w["ay"]), (w["bx"], w["by"])):
            key = None
            for k in ends:
                if math.hypot(k[0] - x, k[1] - y) <= tol:
                    key = k
            ends.setdefault(key or (x, y), []).append(w)
    guarded = []
    for P, ws in ends.items():
        is_point = any(math.hypot(P[0] - q[0], P[1] - q[1]) <= tol for q in pts)
        if not is_point or len(ws) > 1:
            guarded.append((P, is_point, ws))
    S["guarded"] = guarded
    S["guard_cand"] = []


def guard():
    """Before the interaction loop (positions of this step are final): vertex contacts at guarded
    ends are switched off unless the engine has them (a point no adjacent wall owns)."""
    try:
        S["guard_steps"] += 1
        for k in S["guard_cand"]:
            if not S["present"][k]:
                continue
            bid = S["disc_ids"][k]
            s = O.bodies[bid].state
            x, y = s.pos[0], s.pos[1]
            r = S["props"][k][2]
            for P, is_point, ws in S["guarded"]:
                if math.hypot(x - P[0], y - P[1]) > r * 1.001:
                    continue
                us = [(w, _proj(w, x, y)) for w in ws]
                owned = any(0.0 <= u <= 1.0 for _w, u in us)
                first = True
                for w, u in us:
                    if 0.0 <= u <= 1.0:
                        continue          # a plane contact of w: always the engine's
                    legit = is_point and not owned and first
                    first = False
                    if O.interactions.has(w["id"], bid):
                        I = O.interactions[w["id"], bid]
                        if I.isActive != legit:
                            S["guard_flips"] += 1
                        I.isActive = legit
    except Exception:
        _fail("guard: " + traceback.format_exc(limit=3))


# ---------------------------------------------------------------------------------------------
def mover():
    """Last engine before the integrator: a moving wall's facet gets its velocity for the step the
    integrator is about to take (iteration n moves from n dt to (n + 1) dt; the window's steps are
    i_from <= n < i_until, as in the engine), and its bookkeeping ends (guard, contact points)
    are put where that step takes it."""
    try:
        it = O.iter
        dt = S["case"]["dt"]
        busy = False
        for w in S["walls"]:
            if not w.get("motion") or not w["present"]:
                continue
            vx, vy, k0, k1, ax, ay, bx, by = w["motion"]
            on = k0 <= it < k1
            O.bodies[w["id"]].state.vel = Vector3(vx, vy, 0.0) if on else Vector3(0.0, 0.0, 0.0)
            steps = min(max(it + (1 if on else 0), k0), k1) - k0
            w["ax"], w["ay"] = ax + vx * steps * dt, ay + vy * steps * dt
            w["bx"], w["by"] = bx + vx * steps * dt, by + vy * steps * dt
            busy = busy or it < k1
        if not busy:
            mover_engine.dead = True
    except Exception:
        _fail("mover: " + traceback.format_exc(limit=3))


# ---------------------------------------------------------------------------------------------
def remover():
    """Start of a step after the opening: discs whose centre is below outlet_y are erased."""
    try:
        C = S["case"]
        yo = C["outlet_y"]
        it = O.iter
        for k in list(S["rem_cand"]):
            if not S["present"][k]:
                S["rem_cand"].remove(k)
                continue
            s = O.bodies[S["disc_ids"][k]].state
            if s.pos[1] < yo:
                S["removals"].append((it, k, s.vel[0], s.vel[1]))
                O.bodies.erase(S["disc_ids"][k])
                S["present"][k] = False
                S["rem_cand"].remove(k)
    except Exception:
        _fail("remover: " + traceback.format_exc(limit=3))


# ---------------------------------------------------------------------------------------------
def _wall_contacts(record_pairs=False):
    """Per-contact force BY THE DISC ON THE WALL, as the law applied it this step."""
    out = []
    worst = 0.0
    for w in S["walls"]:
        if not w["present"]:
            continue
        wid = w["id"]
        tot = [0.0, 0.0]
        for I in O.interactions.withBody(wid):
            if not I.isReal or not I.isActive:
                continue
            g, p = I.geom, I.phys
            if g.penetrationDepth < 0:
                continue
            other = I.id2 if I.id1 == wid else I.id1
            s1, s2 = O.bodies[I.id1].state, O.bodies[I.id2].state
            fn, fs = p.normalForce, p.shearForce
            F = fn + fs
            mu = p.tangensOfFrictionAngle
            max2 = fn.squaredNorm() * mu * mu
            if fs.squaredNorm() < max2 * (1.0 - 1e-11):   # sticking: the law added cs * v_shear
                cp = g.contactPoint
                c1, c2 = cp - s1.pos, cp - s2.pos
                rel = (s1.vel + s1.angVel.cross(c1)) - (s2.vel + s2.angVel.cross(c2))
                n = g.normal
                vs = rel - n.dot(rel) * n
                F = F + p.cs * vs
            # the law adds -F to id1 and +F to id2
            fx, fy = (-F[0], -F[1]) if I.id1 == wid else (F[0], F[1])
            ds = O.bodies[other].state
            px, py = _clamped_point(w, ds.pos[0], ds.pos[1])
            u = _proj(w, ds.pos[0], ds.pos[1])
            out.append((w["name"], px, py, fx, fy, 0 if 0.0 <= u <= 1.0 else 1))
            tot[0] += fx
            tot[1] += fy
            if record_pairs and w["name"] not in S["pairs_seen"]:
                S["pairs_seen"][w["name"]] = {"kn": p.kn, "cn": p.cn, "ks": p.ks, "cs": p.cs,
                                              "mu": p.tangensOfFrictionAngle}
        f = O.forces.f(wid, True)
        scale = max(1e-300, math.hypot(f[0], f[1]), math.hypot(tot[0], tot[1]))
        worst = max(worst, math.hypot(f[0] - tot[0], f[1] - tot[1]) / scale if (tot != [0.0, 0.0] or
                                                                               f[0] or f[1]) else 0.0)
    S["mismatch"] = max(S["mismatch"], worst)
    return out


def _disc_disc_pair():
    if "disc_disc" in S["pairs_seen"]:
        return
    for I in O.interactions:
        if I.isReal and I.id1 in S["disc_set"] and I.id2 in S["disc_set"]:
            p = I.phys
            S["pairs_seen"]["disc_disc"] = {"kn": p.kn, "cn": p.cn, "ks": p.ks, "cs": p.cs,
                                            "mu": p.tangensOfFrictionAngle}
            return


def _elastic_energy():
    e = 0.0
    for I in O.interactions:
        if I.isReal and I.geom.penetrationDepth > 0:
            e += 0.5 * I.phys.kn * I.geom.penetrationDepth ** 2
    return e


def _scan():
    """State of all present discs: checks, energy, candidate lists for the guard and remover."""
    C = S["case"]
    gx, gy = S["g"]
    box = C["box"]
    contained = C["contained"]
    below_ok = S["gate_open"]
    ke = pe = 0.0
    vmax = 0.0
    rows = []
    for k, bid in enumerate(S["disc_ids"]):
        if not S["present"][k]:
            continue
        b = O.bodies[bid]
        if b is None:
            return f"disc {k} (body {bid}) vanished from YADE's body container"
        s = b.state
        x, y, vx, vy, om = s.pos[0], s.pos[1], s.vel[0], s.vel[1], s.angVel[2]
        if not _finite(x, y, vx, vy, om):
            return f"non-finite state of disc {k} at step {O.iter}: x={x!r} y={y!r} vx={vx!r} vy={vy!r} omega={om!r}"
        m, inertia, r = S["props"][k]
        if contained and (x < box[0] or x > box[1] or y > box[3] or (y < box[2] and not below_ok)):
            return (f"disc {k} left the container at step {O.iter}: centre ({x!r}, {y!r}) outside "
                    f"the walls' box enlarged by 2 r {box!r}")
        ke += 0.5 * m * (vx * vx + vy * vy) + 0.5 * inertia * om * om
        pe += m * (-(gx * x + gy * y) - C["pe_ref"])
        vmax = max(vmax, math.hypot(vx, vy))
        rows.append((k, x, y, r))
    S["ke"] = ke
    S["ke_max"] = max(S["ke_max"], ke)
    if S["E0"] is None:
        S["E0"] = ke + pe + _elastic_energy()
    elif ke + pe > 1.5 * S["E0"] + 1e-9 * (abs(S["E0"]) + C["energy_scale"]):
        return (f"blow-up at step {O.iter}: kinetic + potential energy {ke + pe!r} exceeds 1.5 x the "
                f"initial energy budget {S['E0']!r} (kinetic {ke!r})")
    # Candidate lists valid until the next scan (scan_every steps): band = reach in that time.
    T = C["scan_every"] * S["dt"]
    gmag = math.hypot(gx, gy)
    band = 2.0 * (vmax * T + 0.5 * gmag * T * T) + 0.05 * C["rmax"]
    if S["guarded"]:
        cand = []
        for k, x, y, r in rows:
            for P, _ip, _ws in S["guarded"]:
                if math.hypot(x - P[0], y - P[1]) <= r + band:
                    cand.append(k)
                    break
        S["guard_cand"] = cand
        guard_engine.dead = not cand
    if S["gate_open"] and C["outlet_y"] is not None:
        S["rem_cand"] = [k for k, x, y, r in rows if y < C["outlet_y"] + band]
        remover_engine.dead = not S["rem_cand"]
    return None


def scan():
    """Every scan_every steps, after the forces of this step and before the integrator."""
    try:
        if S["failed"]:
            return
        err = _scan()
        if err:
            _fail(err)
    except Exception:
        _fail("scan: " + traceback.format_exc(limit=3))


def monitor():
    """Every sample_every steps from the start (static) or the opening (discharge), after the
    forces of this step and before the integrator."""
    try:
        if S["failed"]:
            return
        it = O.iter
        io = S["i_open"]
        if it >= io and (it - io) % S["case"]["sample_every"] == 0 and it <= S["i_end"]:
            t = (it - io) * S["dt"]
            S["series_t"].append(t)
            for c in _wall_contacts(record_pairs=True):
                S["series_rows"].append((t,) + c)
        _disc_disc_pair()
    except Exception:
        _fail("monitor: " + traceback.format_exc(limit=3))


def final():
    """The last step (i_end), after the forces and before the integrator."""
    try:
        dt = S["dt"]
        gx, gy = S["g"]
        contacts = _wall_contacts(record_pairs=True)
        discs, kept = [], []
        ke = 0.0
        for k, bid in enumerate(S["disc_ids"]):
            if not S["present"][k]:
                continue
            s = O.bodies[bid].state
            m, inertia, r = S["props"][k]
            f, tq = O.forces.f(bid, True), O.forces.t(bid, True)
            # leapfrog: vel holds v(n - 1/2); v(n) = v(n - 1/2) + a(n) dt / 2
            vx = s.vel[0] + 0.5 * dt * (f[0] / m + gx)
            vy = s.vel[1] + 0.5 * dt * (f[1] / m + gy)
            om = s.angVel[2] + 0.5 * dt * tq[2] / inertia
            discs.append([s.pos[0], s.pos[1], r, vx, vy, om])
            kept.append(k)
            ke += 0.5 * m * (vx * vx + vy * vy) + 0.5 * inertia * om * om
        S["final"] = {"contacts": contacts, "discs": discs, "kept": kept, "ke": ke, "iter": O.iter}
        err = _scan()
        if err:
            _fail(err)
    except Exception:
        _fail("final: " + traceback.format_exc(limit=3))


def _fail(reason):
    if not S.get("failed"):
        S["failed"] = reason
    O.pause()


# ---------------------------------------------------------------------------------------------
def _run(n):
    if n > 0 and not S["failed"]:
        t = time.time()
        O.run(n, True)
        S["loop_time"] += time.time() - t


def write_outputs(status, reason, t_start):
    C = S.get("case", {})
    fin = S.get("final") or {}
    io = S.get("i_open", 0)
    dt = S.get("dt", float("nan"))
    n0 = len(S.get("disc_ids", []))
    i_end_done = fin.get("iter", O.iter)
    removed_steps = [i for i, _k, _vx, _vy in S.get("removals", [])]
    particle_steps = n0 * i_end_done - sum(i_end_done - i for i in removed_steps)
    res = {
        "status": status, "reason": reason,
        "yade_version": version(),
        "steps": i_end_done if fin else O.iter,
        "n_initial": n0,
        "n_final": sum(S.get("present", [])),
        "removals": [{"t": (i - io) * dt, "step": i, "index": k, "vx": vx, "vy": vy}
                     for i, k, vx, vy in S.get("removals", [])],
        "series_t": S.get("series_t", []),
        "final_contacts": [list(c) for c in fin.get("contacts", [])],
        "discs_end": fin.get("discs", []),
        "kept_index": fin.get("kept", []),
        "disc_body_ids": S.get("disc_ids", []),
        "kinetic_energy_end": fin.get("ke", float("nan")),
        "kinetic_energy_max_sampled": S.get("ke_max", float("nan")),
        "energy_budget": S.get("E0"),
        "loop_time_s": S.get("loop_time", 0.0),
        "script_time_s": time.time() - t_start,
        "particle_steps": particle_steps,
        "wall_force_mismatch_rel": S.get("mismatch", 0.0),
        "guard_steps": S.get("guard_steps", 0),
        "guard_flips": S.get("guard_flips", 0),
        "pairs_seen": S.get("pairs_seen", {}),
        "threads": O.numThreads,
    }
    with open(SERIES_FILE + ".tmp", "w") as fh:
        fh.write("t,wall,px,py,fx,fy,vertex\n")
        for t, name, px, py, fx, fy, v in S.get("series_rows", []):
            fh.write(f"{t!r},{name},{px!r},{py!r},{fx!r},{fy!r},{v}\n")
    os.replace(SERIES_FILE + ".tmp", SERIES_FILE)
    with open(RESULT_FILE + ".tmp", "w") as fh:
        json.dump(res, fh, indent=1)
    os.replace(RESULT_FILE + ".tmp", RESULT_FILE)


def version():
    try:
        import yade.config
        return "yade " + str(yade.config.version)
    except Exception:
        return "yade (version unknown)"


def main():
    t_start = time.time()
    S["loop_time"] = 0.0
    try:
        setup()
        S["disc_set"] = set(S["disc_ids"])
        C = S["case"]
        if C["mode"] == "discharge":
            _run(S["i_open"])
            if not S["failed"]:
                for w in S["walls"]:
                    if w["name"] == C["gate"] and w["present"]:
                        O.bodies.erase(w["id"])
                        w["present"] = False
                S["gate_open"] = True
                S["rem_cand"] = []
                _update_guarded_ends()
                # next monitor call exactly at the opening, then every sample_every steps
                monitor_engine.iterLast = O.iter - C["sample_every"]
                monitor_engine.dead = False
                if C.get("snapshot_every"):
                    snap_engine.iterLast = O.iter - C["snapshot_every"]
                    snap_engine.dead = False
        _run(S["i_end"] - O.iter)
        if not S["failed"]:
            if O.iter != S["i_end"]:
                _fail(f"YADE stopped at step {O.iter} before the end step {S['i_end']}")
            else:
                final_engine.dead = False
                _run(1)
        if not S["failed"] and S.get("final") is None:
            _fail("the final step did not run")
        if not S["failed"]:
            lost = [k for k, bid in enumerate(S["disc_ids"]) if S["present"][k] and O.bodies[bid] is None]
            if lost:
                _fail(f"lost discs: {len(lost)} discs vanished from YADE (first {lost[:5]})")
        if S["failed"]:
            write_outputs("failed", S["failed"], t_start)
        else:
            write_outputs("complete", "", t_start)
    except _InputError as e:
        write_outputs("failed", f"input rejected by the YADE script: {e}", t_start)
    except Exception:
        write_outputs("error", "python error in the YADE script:\n" + traceback.format_exc(limit=5), t_start)
        raise


import os  # noqa: E402  (kept at the end so the header reads as the script's documentation)

if __name__ == "__main__":
    main()
