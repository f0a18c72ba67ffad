# Paper 2's simple shear test in YADE 2023.02a: the shear path of compare/codes/yade_backend.py, run as
# `yade -n -jN -x yade_script.py` in the case's folder, next to yade_case.json (written by
# yade_backend.shear_case_data: every value is there, nothing here is a scene constant). Writes, at
# full precision, into that folder: shear_series.csv, shear_planes.csv, summary.json, snapshots/
# (contacts and discs CSV as the engine's, index.json).
#
# The model (the translation and what differs: compare/codes/yade_backend.py):
# - 2D discs: spheres at z = 0, blockedDOFs 'zXY', mass rho pi r^2, inertia m r^2 / 2 (per cm),
#   each disc with its own material's density;
# - contacts between clusters, free discs, walls and plate: ViscElMat (F_n = kn overlap + cn v_n
#   clamped >= 0, Coulomb cap on the total normal force); the disc and wall materials of
#   yade_backend.materials (series combination: disc material = 2 x its disc-disc pair, wall
#   material solved for the disc-wall pair, 0 = "absent"); friction per material pair by MatchMaker;
# - clusters, mode "bonds": every bonded pair is an interaction made at the start whose physics
#   is replaced by a CohFrictPhys (kn, ks of the pair, normal and shear adhesion 1e30:
#   elastic and unbreakable, no dashpot, lever arms to the bond point at mid-gap); mode "clumps":
#   YADE clumps (rigid clusters, contacts between clumps by the ViscEl law);
# - walls and plate are boxes: the floor fixed, the side walls turned about their lower inner
#   corners by RotationEngines during the shear, the plate a dynamic box with the plate's mass,
#   free in x and y, rotations blocked;
# - NewtonIntegrator(damping=0) (leapfrog), fixed dt.
import json
import math
import os
import time

from yade import *  # noqa: F401,F403  (O, bodies, engines, functors)
from yade import utils

CASE = json.load(open("yade_case.json"))
OUT = os.getcwd()
os.makedirs(os.path.join(OUT, "snapshots"), exist_ok=True)
dt = CASE["dt"]
gx, gy = CASE["gravity"]
box = CASE["box"]
sh = CASE["shear"]
mode = CASE["clusters"]["mode"]
W, L = box["width"], box["wall_length"]
HALF_Z = 2.0

mat_id = {}
for name, d in sorted(CASE["disc_materials"].items()):
    mat_id[name] = O.materials.append(ViscElMat(kn=d["kn"], cn=d["cn"], ks=d["ks"], cs=d["cs"],
                                                density=d["density"], label="disc_" + name))
wall_ids = []
for name, m in sorted(CASE["wall_materials"].items()):
    mat_id[name] = O.materials.append(ViscElMat(kn=m["kn"], cn=m["cn"], ks=m["ks"], cs=m["cs"],
                                                density=1.0, label="wall_" + name))
    wall_ids.append(mat_id[name])
matches = [(mat_id[a], mat_id[b], math.atan(mu)) for a, b, mu in CASE["friction"]]
for a in range(len(wall_ids)):
    for b in range(a, len(wall_ids)):
        matches.append((wall_ids[a], wall_ids[b], 0.0))   # walls never touch each other
wall_of = CASE["wall_material_of"]


def add_box(centre, half, material, fixed=True):
    b = utils.box(center=(centre[0], centre[1], 0), extents=(half[0], half[1], HALF_Z), fixed=fixed,
                  material=mat_id[material], wire=True)
    return O.bodies.append(b)


floor = add_box((0.5 * W, -0.5), (0.5 * W + 3, 0.5), wall_of["floor"])
left = add_box((-0.5, 0.5 * L), (0.5, 0.5 * L), wall_of["left"])
right = add_box((W + 0.5, 0.5 * L), (0.5, 0.5 * L), wall_of["right"])
ov = box["plate_overhang"]
plate = add_box((0.5 * W, box["plate_y"] + 0.5), (0.5 * W + ov, 0.5), wall_of["plate"], fixed=False)
pb = O.bodies[plate]
pb.state.blockedDOFs = "zXYZ"
pb.state.mass = box["plate_mass"]
pb.state.inertia = (1.0, 1.0, 1.0)
WALL_NAMES = {floor: "floor", left: "left", right: "right", plate: "plate"}

discs = []
for (x, y, r, vx, vy, om), name in zip(CASE["discs"], CASE["disc_material_of"]):
    i = O.bodies.append(utils.sphere((x, y, 0), r, material=mat_id[name]))
    b = O.bodies[i]
    m = CASE["disc_materials"][name]["density"] * math.pi * r * r
    b.state.blockedDOFs = "zXY"
    b.state.mass = m
    b.state.inertia = (0.5 * m * r * r,) * 3
    b.state.vel = Vector3(vx, vy, 0.0)
    b.state.angVel = Vector3(0.0, 0.0, om)
    discs.append(i)
disc_index = {bid: k for k, bid in enumerate(discs)}
radius = [row[2] for row in CASE["discs"]]

bonded = set()
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], verletDist=0.1),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom6D(avoidGranularRatcheting=False), Ig2_Box_Sphere_ScGeom6D()],
        [Ip2_ViscElMat_ViscElMat_ViscElPhys(frictAngle=MatchMaker(matches=matches))],
        [Law2_ScGeom_ViscElPhys_Basic(), Law2_ScGeom6D_CohFrictPhys_CohesionMoment()]),
    RotationEngine(rotateAroundZero=True, zeroPoint=(0, 0, 0), rotationAxis=(0, 0, -1),
                   angularVelocity=sh["rate"], ids=[left], dead=True, label="turn_left"),
    RotationEngine(rotateAroundZero=True, zeroPoint=(W, 0, 0), rotationAxis=(0, 0, -1),
                   angularVelocity=sh["rate"], ids=[right], dead=True, label="turn_right"),
    NewtonIntegrator(damping=0, gravity=(gx, gy, 0)),
]
O.dt = dt

if mode == "bonds":
    for i, j, kn, ks in CASE["clusters"]["bonds"]:
        inter = utils.createInteraction(discs[i], discs[j])
        ph = CohFrictPhys()
        ph.kn, ph.ks = kn, ks
        ph.normalAdhesion = ph.shearAdhesion = 1e30
        ph.cohesionBroken = False
        ph.tangensOfFrictionAngle = 0.0  # never used: the bond never breaks
        ph.unp = inter.geom.penetrationDepth  # the bond is unloaded as built
        inter.phys = ph
        bonded.add((min(discs[i], discs[j]), max(discs[i], discs[j])))
elif mode == "clumps":
    for members in CASE["clusters"]["members"]:
        ids = [discs[i] for i in members]
        cid = O.bodies.clump(ids)
        c = O.bodies[cid]
        m = sum(O.bodies[i].state.mass for i in ids)
        cx = sum(O.bodies[i].state.mass * O.bodies[i].state.pos[0] for i in ids) / m
        cy = sum(O.bodies[i].state.mass * O.bodies[i].state.pos[1] for i in ids) / m
        inertia = sum(O.bodies[i].state.inertia[2] + O.bodies[i].state.mass *
                      ((O.bodies[i].state.pos[0] - cx) ** 2 + (O.bodies[i].state.pos[1] - cy) ** 2) for i in ids)
        c.state.blockedDOFs = "zXY"
        c.state.mass = m
        c.state.inertia = (inertia,) * 3

WEIGHT = sum(O.bodies[i].state.mass for i in discs) * math.hypot(gx, gy)
PLATE_WEIGHT = box["plate_mass"] * math.hypot(gx, gy)


def f17(v):
    return "%.17g" % v


def contact_forces():
    """(sphere-sphere list, sphere-box list) of (id1, id2, force on id2 (x, y), point, normal)."""
    ss, sb = [], []
    for I in O.interactions:
        if not I.isReal:
            continue
        F = I.phys.normalForce + I.phys.shearForce
        rec = (I.id1, I.id2, (F[0], F[1]), (I.geom.contactPoint[0], I.geom.contactPoint[1]),
               (I.geom.normal[0], I.geom.normal[1]))
        (ss if I.id1 in disc_index and I.id2 in disc_index else sb).append(rec)
    return ss, sb


def plane_stresses(planes):
    ss, sb = contact_forces()
    pos = {i: (O.bodies[i].state.pos[0], O.bodies[i].state.pos[1]) for i in discs}
    out = []
    for yk in planes:
        fx = fy = 0.0
        n = 0
        for a, b, F, _, _ in ss:
            ya, yb = pos[a][1], pos[b][1]
            if (ya < yk) == (yb < yk):
                continue
            # force on the part below: on a = -F if a is below, on b = F if b is below
            s = -1.0 if ya < yk else 1.0
            fx += s * F[0]
            fy += s * F[1]
            n += 1
        # check: weight and wall/plate forces on the discs above
        cx = cy = 0.0
        for i in discs:
            if pos[i][1] > yk:
                cx += O.bodies[i].state.mass * gx
                cy += O.bodies[i].state.mass * gy
        for a, b, F, _, _ in sb:
            d = b if b in disc_index else a
            if pos[d][1] > yk:
                s = 1.0 if d == b else -1.0
                cx += s * F[0]
                cy += s * F[1]
        out.append((yk, n, -fy / W, fx / W, -cy / W, cx / W))
    return out


def mean_speed():
    sx = sy = 0.0
    for i in discs:
        v = O.bodies[i].state.vel
        sx += abs(v[0])
        sy += abs(v[1])
    return sx / len(discs), sy / len(discs)


def kinetic():
    e = 0.0
    for i in discs:
        s = O.bodies[i].state
        e += 0.5 * s.mass * (s.vel[0] ** 2 + s.vel[1] ** 2) + 0.5 * s.inertia[2] * s.angVel[2] ** 2
    return e


# ---------------------------------------------------------------- compression to rest
g = math.hypot(gx, gy)
rest_speed = CASE["compress"]["rest_factor"] * g * dt  # mean |du| < rest_factor g dt^2 per step
check = max(1, int(round(0.005 / dt)))
t0 = time.time()
rest_time = None
max_steps = int(round(CASE["compress"]["max_time"] / dt))
steps = 0
while steps < max_steps:
    O.run(check, True)
    steps += check
    mx, my = mean_speed()
    if not (math.isfinite(mx) and math.isfinite(my)):
        raise SystemExit("yade shear: non-finite velocities in the compression")
    if mx < rest_speed and my < rest_speed:
        rest_time = O.time
        break
compress_time = O.time

# ---------------------------------------------------------------- shear
ys = sorted((O.bodies[i].state.pos[1], i) for i in discs)
rmean = sum(radius) / len(radius)
rows = []
for y, i in ys:
    if not rows or y - O.bodies[rows[-1][-1]].state.pos[1] > 0.5 * rmean:
        rows.append([])
    rows[-1].append(i)


def plane_heights():
    means = [sum(O.bodies[i].state.pos[1] for i in r) / len(r) for r in rows]
    return [0.5 * (means[k] + means[k + 1]) for k in range(len(means) - 1)]


series = ["t,strain,angle,sigma,tau,ratio,sigma_check,tau_check,sigma_plate,tau_plate,plate_x,plate_y,"
          "left_fx,left_fy,right_fx,right_fy,floor_fx,floor_fy,contacts,kinetic_energy"]
planes_csv = ["t,strain,plane,y,contacts,sigma,tau,sigma_check,tau_check"]
snaps = []
plate_x0, plate_y0 = pb.state.pos[0], pb.state.pos[1]
samples = []


def walls_now(theta):
    s, c = math.sin(theta), math.cos(theta)
    px, py = pb.state.pos[0], pb.state.pos[1] - 0.5
    return [{"name": "left", "from": [L * s, L * c], "to": [0.0, 0.0]},
            {"name": "right", "from": [W + L * s, L * c], "to": [W, 0.0]},
            {"name": "floor", "from": [0.0, 0.0], "to": [W, 0.0]},
            {"name": "plate", "from": [px - 0.5 * W - ov, py], "to": [px + 0.5 * W + ov, py]}]


def snapshot(k, strain, wanted, theta):
    ss, sb = contact_forces()
    lines = ["kind,i,j,x,y,nx,ny,e_n,e_s,f_n,f_s"]
    for a, b, F, p, n in ss:
        t = (-n[1], n[0])
        fn = F[0] * n[0] + F[1] * n[1]
        fs = F[0] * t[0] + F[1] * t[1]
        kind = "db" if (min(a, b), max(a, b)) in bonded else "dd"
        lines.append(",".join([kind, str(disc_index[a]), str(disc_index[b])] + [f17(v) for v in (p[0], p[1], n[0], n[1], fn, fs, fn, fs)]))
    for a, b, F, p, n in sb:
        d, w = (b, a) if b in disc_index else (a, b)
        s = 1.0 if d == b else -1.0          # YADE's normal runs from id1 to id2
        nx, ny = -s * n[0], -s * n[1]         # from the disc to the wall
        fwx, fwy = -s * F[0], -s * F[1]       # force on the wall
        t = (-ny, nx)
        fn = fwx * nx + fwy * ny
        fs = fwx * t[0] + fwy * t[1]
        lines.append(",".join(["dw", str(disc_index[d]), WALL_NAMES.get(w, str(w))] +
                              [f17(v) for v in (p[0], p[1], nx, ny, fn, fs, fn, fs)]))
    name = "%02d" % k
    with open(os.path.join(OUT, "snapshots", f"contacts_{name}.csv"), "w") as f:
        f.write("\n".join(lines) + "\n")
    dl = ["id,x,y,r,vx,vy,omega,material"]
    for k2, i in enumerate(discs):
        s = O.bodies[i].state
        dl.append(",".join([str(k2)] + [f17(v) for v in (s.pos[0], s.pos[1], radius[k2], s.vel[0], s.vel[1], s.angVel[2])] + [CASE["disc_material_of"][k2]]))
    with open(os.path.join(OUT, "snapshots", f"discs_{name}.csv"), "w") as f:
        f.write("\n".join(dl) + "\n")
    snaps.append({"strain": strain, "strain_wanted": wanted, "t": O.time - compress_time,
                  "contacts": f"contacts_{name}.csv", "discs": f"discs_{name}.csv", "walls": walls_now(theta)})


# Clumps carry force inside themselves, where no interaction records it: a plane that a clump
# crosses would miss that force. Clumps then use only the planes that no clump crosses (between
# the pairs of rows that the clusters tile).
row_of = {i: k for k, r in enumerate(rows) for i in r}
crossed = set()
for members in (CASE["clusters"].get("members", []) if mode == "clumps" else []):
    rr = sorted({row_of[discs[i]] for i in members})
    crossed.update(range(rr[0], rr[-1]))
USE_PLANES = [k for k in range(len(rows) - 1) if k not in crossed]


def sample(theta):
    strain = math.tan(theta)
    heights = plane_heights()
    ps = plane_stresses([heights[k] for k in USE_PLANES])
    t = O.time - compress_time
    sig = sum(p[2] for p in ps) / len(ps)
    tau = sum(p[3] for p in ps) / len(ps)
    sc = sum(p[4] for p in ps) / len(ps)
    tc = sum(p[5] for p in ps) / len(ps)
    for k, p in zip(USE_PLANES, ps):
        planes_csv.append(",".join([f17(t), f17(strain), str(k), f17(p[0]), str(p[1])] + [f17(v) for v in p[2:]]))
    fp = O.forces.f(plate)
    fl, fr, ff = O.forces.f(left), O.forces.f(right), O.forces.f(floor)
    n_contacts = sum(1 for I in O.interactions if I.isReal)
    ratio = tau / sig if sig != 0 else 0.0
    samples.append((strain, ratio, sig))
    series.append(",".join(f17(v) for v in (
        t, strain, theta, sig, tau, ratio, sc, tc, fp[1] / W, -fp[0] / W, pb.state.pos[0] - plate_x0,
        pb.state.pos[1] - plate_y0, fl[0], fl[1], fr[0], fr[1], ff[0], ff[1])) + f",{n_contacts}," + f17(kinetic()))


theta_end = math.atan(sh["max_strain"])
every = max(1, int(round(sh["sample_strain"] / (sh["rate"] * dt))))
total = int(math.ceil(theta_end / (sh["rate"] * dt) - 1e-9))
O.engines[3].dead = False
O.engines[4].dead = False
wanted = sorted(sh["snapshots"])
k_snap = 0
status = "sheared"
n_steps = 0
while True:
    theta = sh["rate"] * n_steps * dt
    strain = math.tan(theta)
    sample(theta)
    while k_snap < len(wanted) and strain >= wanted[k_snap] - 1e-9:
        snapshot(k_snap, strain, wanted[k_snap], theta)
        k_snap += 1
    if n_steps >= total:
        break
    n = min(every, total - n_steps)
    O.run(n, True)
    n_steps += n
    mx, my = mean_speed()
    if not (math.isfinite(mx) and math.isfinite(my)):
        status = "unstable"
        break

with open(os.path.join(OUT, "shear_series.csv"), "w") as f:
    f.write("\n".join(series) + "\n")
with open(os.path.join(OUT, "shear_planes.csv"), "w") as f:
    f.write("\n".join(planes_csv) + "\n")
with open(os.path.join(OUT, "snapshots", "index.json"), "w") as f:
    json.dump({"snapshots": snaps}, f, indent=1)
kmax = max(range(len(samples)), key=lambda k: samples[k][1])
summary = {
    "engine": "yade " + str(getattr(__import__("yade.config").config, "version", "?")),
    "status": status,
    "clusters": mode,
    "dt": dt,
    "rest": {"reached": rest_time is not None, "time": rest_time, "compression_time": compress_time},
    "disc_weight": O.bodies[discs[0]].state.mass * g,
    "kinetic_energy_end": kinetic(),
    "discs_end": [[O.bodies[i].state.pos[0], O.bodies[i].state.pos[1], radius[k], O.bodies[i].state.vel[0],
                   O.bodies[i].state.vel[1], O.bodies[i].state.angVel[2]] for k, i in enumerate(discs)],
    "walls": walls_now(theta),
    "shear": {"width": W, "rate": sh["rate"], "plate_weight": PLATE_WEIGHT, "discs_weight": WEIGHT,
              "rows": len(rows), "planes": len(USE_PLANES), "bonds": len(bonded), "samples": len(samples),
              "sigma_initial": samples[0][2], "peak_ratio": samples[kmax][1], "strain_at_peak": samples[kmax][0],
              "ratio_final": samples[-1][1], "strain_final": samples[-1][0],
              "plate_final": [pb.state.pos[0] - plate_x0, pb.state.pos[1] - plate_y0]},
    "wall_time_s": time.time() - t0,
    "steps": O.iter,
}
with open(os.path.join(OUT, "summary.json"), "w") as f:
    json.dump(summary, f, indent=1)
