#!/usr/bin/python3
"""drivetrain_cli's numbers against independent sources (issue 15 §6: the regex CLI checks pass on
a NaN, which JSON writes as null). Each check recomputes the value here, from the physics, not from
the tool's own code:

- bearing: the ball loads balance the applied load (Harris & Kotzalas, Rolling Bearing Analysis,
  5th ed., eqs. (7.56)-(7.57): F_a = sum Q_j sin(alpha_j), F_r = sum Q_j cos(alpha_j) cos(psi_j));
  the tangent stiffness matrix, condensed over the free axial displacement, equals a finite
  difference of the solved radial displacement at constant axial force.
- mesh: contact ratio, base radii and base pitch from the involute geometry of the gearbox YAML
  (ISO 21771 / Litvin, Gear Geometry, ch. 10: eps = [sqrt(ra1^2-rb1^2) + sqrt(ra2^2-rb2^2)
  - a sin(alpha)] / (pi m cos(alpha))).
- modes: the natural frequencies of the 3-DOF transverse-torsional model (seed 000 §3, the
  Kahraman-Singh form: coordinates x (mesh, on the equivalent mass), x_p, x_g; delta = x + x_p - x_g)
  built here with numpy from the masses and stiffnesses the tool reports.
- simulate and sweep: every number finite, the sweep grid exact, the sweep's response peaks within
  3 % of the modes above.
Usage: check_cli_values.py DRIVETRAIN_CLI SOURCE_DIR
"""

import json
import math
import subprocess
import sys

import numpy as np
import yaml

CLI, SRC = sys.argv[1], sys.argv[2]
failures = []


def run(*args):
    out = subprocess.run([CLI, *args], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def check(name, ok, detail=""):
    print(("ok   " if ok else "FAIL ") + name + (f": {detail}" if detail else ""))
    if not ok:
        failures.append(name)


def close(name, got, want, rtol):
    ok = got is not None and math.isfinite(got) and abs(got - want) <= rtol * abs(want)
    check(name, ok, f"{got!r} against {want!r} (rtol {rtol:g})")


def finite_numbers(name, value, nulls=()):
    """Every number finite, and no null but the listed fields' (the tool writes NaN as null)."""
    bad = []

    def walk(v, path):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(x, f"{path}.{k}")
        elif isinstance(v, list):
            for i, x in enumerate(v):
                walk(x, f"{path}[{i}]")
        elif (isinstance(v, float) and not math.isfinite(v)) or (v is None and path not in nulls):
            bad.append(path)
    walk(value, name)
    check(f"{name}: every number finite, no null", not bad, ", ".join(bad[:5]))


bearing_cfg = f"{SRC}/config/bearings/7013ac.yaml"
gearbox = f"{SRC}/config/gearboxes/seed_servo.yaml"

# --- bearing: equilibrium and the condensed radial stiffness -------------------------------------
b = run("bearing", "--config", bearing_cfg, "--fa", "1000", "--fr", "500")
b2 = run("bearing", "--config", bearing_cfg, "--fa", "1000", "--fr", "505")
check("bearing converged", b["converged"] is True and b2["converged"] is True)
Q = b["ball_loads"]
alpha = [math.radians(a) for a in b["contact_angles_deg"]]
Z = len(Q)
close("bearing: sum Q sin(alpha) = axial load", sum(q * math.sin(a) for q, a in zip(Q, alpha)), b["load"]["force_z"], 1e-6)
close("bearing: sum Q cos(alpha) cos(psi) = radial load",
      sum(q * math.cos(a) * math.cos(2 * math.pi * j / Z) for j, (q, a) in enumerate(zip(Q, alpha))), 500.0, 1e-6)
K = np.array(b["stiffness"]["matrix"])
check("bearing: stiffness matrix symmetric", np.allclose(K, K.T, rtol=1e-6, atol=1e-6 * abs(K).max()))
condensed = K[0, 0] - K[0, 2] * K[2, 0] / K[2, 2]  # x radial, z axial (dofs u_x, u_y, u_z, theta_x, theta_y)
fd = 5.0 / (b2["displacement"]["radial"] - b["displacement"]["radial"])
close("bearing: condensed tangent radial stiffness = finite difference (5 N)", condensed, fd, 1e-3)
finite_numbers("bearing", b)

# --- mesh: involute geometry ----------------------------------------------------------------------
with open(gearbox) as f:
    g = yaml.safe_load(f)["gears"]
m, z1, z2 = g["module"], g["teeth"][0], g["teeth"][1]
al = math.radians(g["pressure_angle_deg"])
r1, r2 = m * z1 / 2, m * z2 / 2
ra1, ra2 = r1 + g["addendum_coefficient"] * m, r2 + g["addendum_coefficient"] * m
rb1, rb2 = r1 * math.cos(al), r2 * math.cos(al)
a = r1 + r2  # standard centre distance (the YAML omits it: tight mesh)
eps = (math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - a * math.sin(al)) / (math.pi * m * math.cos(al))
mesh = run("mesh", "--config", gearbox, "--samples", "20")
geo = mesh["geometry"]
close("mesh: contact ratio", geo["contact_ratio"], eps, 1e-9)
close("mesh: pinion base radius", geo["base_radius"][0], rb1, 1e-12)
close("mesh: gear base radius", geo["base_radius"][1], rb2, 1e-12)
close("mesh: base pitch", geo["base_pitch"], math.pi * m * math.cos(al), 1e-12)
close("mesh: centre distance", geo["center_distance"], a, 1e-12)
check("mesh: k_min <= k_mean <= k_max", mesh["ks"]["min"] <= mesh["ks"]["mean"] <= mesh["ks"]["max"])
finite_numbers("mesh", mesh)

# --- modes: the 3-DOF eigenproblem rebuilt here ------------------------------------------------------
modes = run("modes", "--config", gearbox)
M_ = modes["masses"]
S = modes["stiffness"]
M = np.diag([M_["equivalent_mass"], M_["pinion_mass"], M_["gear_mass"]])
expected = {}
for label, key in (("mesh_single_pair", "mesh_min"), ("mesh_mean", "mesh_mean"), ("mesh_double_pair", "mesh_max")):
    km, kp, kg = S[key], S["pinion_bearing"], S["gear_bearing"]
    Kmat = np.array([[km, km, -km], [km, km + kp, -km], [-km, -km, km + kg]])
    f = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, Kmat)).real)) / (2 * math.pi)
    expected[label] = f
    for i in range(3):
        close(f"modes: {label} mode {i + 1}", modes["modes"][label][i]["natural_frequency_hz"], f[i], 1e-6)
# the equivalent mass of the torsional coordinate: I_p I_g / (I_p r_bg^2 + I_g r_bp^2)
Ip, Ig = M_["pinion_inertia"], M_["gear_inertia"]
close("modes: equivalent mass", M_["equivalent_mass"], Ip * Ig / (Ip * rb2**2 + Ig * rb1**2), 1e-9)
check("modes: stable", modes["floquet"]["stable"] is True)
finite_numbers("modes", modes)

# --- simulate and sweep -----------------------------------------------------------------------------
sim = run("simulate", "--config", gearbox, "--scene", "nominal", "--duration", "0.005")
finite_numbers("simulate", sim, nulls=("simulate.auto", "simulate.csv", "simulate.step"))  # not asked for; adaptive
check("simulate: TE statistics present and positive",
      all(isinstance(sim[c][s], float) and sim[c][s] > 0 for c in ("delta", "x", "x_p", "x_g") for s in ("peak", "rms")))
sweep = run("sweep", "--config", gearbox, "--start", "6000", "--stop", "11000", "--step", "250", "--fidelity", "linear_modal")
finite_numbers("sweep", sweep)
check("sweep: the frequency grid", sweep["frequency_hz"] == [6000.0 + 250.0 * i for i in range(21)])
peaks = [p["frequency_hz"] for p in sweep["coordinates"]["x"]["peaks"]]
for i, want in enumerate(expected["mesh_mean"][:2]):
    check(f"sweep: a response peak within 3 % of mode {i + 1} ({want:.0f} Hz)",
          any(abs(p - want) <= 0.03 * want for p in peaks), f"peaks {peaks}")

print(f"{len(failures)} failed" if failures else "all passed")
sys.exit(1 if failures else 0)
