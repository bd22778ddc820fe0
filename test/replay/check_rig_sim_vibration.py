#!/usr/bin/env python3
"""drivetrain_rig_sim's accelerometers (docs/vibration.md "Simulated accelerometers").

1. Blocks: the requested rate and size, the two supports' channels, contiguous stamps at the first
   sample, header.seq counting, finite values; drivetrain_replay --vibration-topic accepts every
   block with no gap; the other topics' messages are those of --vibration-rate 0, which writes no
   vibration topic.
2. Physics: the Welch spectrum of each channel at constant speed peaks at the modal analysis'
   natural frequencies (drivetrain_cli modes, an eigen-solution independent of the time simulation)
   within 1 %, for the seed gearbox and for one with the pinion bearing's stiffness_scale 0.8, whose
   pinion-shaft peak moves as predicted while the gear-shaft peak stays.
3. Anti-alias: above the filter's stop band edge (0.45 x the rate) the spectrum is the sensor-noise
   floor 2 sigma^2 / fs; without sensor noise it is over 80 dB below the spectrum at 0.2-0.3 x the
   rate, whose content would fold without the filter.
usage: check_rig_sim_vibration.py BIN_DIR SOURCE_DIR WORK_DIR
"""
import json
import math
import os
import subprocess
import sys

import numpy as np
import rosbag

bin_dir, src, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
seed_yaml = os.path.join(src, "config/gearboxes/seed_servo.yaml")
EPOCH = 1767225600.0  # drivetrain_rig_sim's default --epoch [s]
failures = []


def check(ok, what):
    print(("ok: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def rig_sim(out, *args, config=seed_yaml):
    cmd = [os.path.join(bin_dir, "drivetrain_rig_sim"), "--config", config, "--out", out] + list(args)
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)


def read_blocks(path, topic="/vibration"):
    blocks = []
    with rosbag.Bag(path) as bag:
        for _, m, t in bag.read_messages(topics=[topic]):
            blocks.append((m, t))
    return blocks


def samples(blocks):
    return np.concatenate(
        [np.asarray(m.data, dtype=np.float64).reshape(-1, len(m.channels)) for m, _ in blocks])


def welch(x, fs, n=4096):
    """One-sided PSD [(m/s^2)^2/Hz], Hann window, half overlap."""
    w = np.hanning(n)
    segs = [x[i:i + n] for i in range(0, len(x) - n + 1, n // 2)]
    p = np.mean([np.abs(np.fft.rfft((s - s.mean()) * w))**2 for s in segs], axis=0)
    return np.fft.rfftfreq(n, 1.0 / fs), p * 2.0 / (fs * np.sum(w**2))


def modes(config, torque):
    out = subprocess.run([os.path.join(bin_dir, "drivetrain_cli"), "modes", "--config", config,
                          "--torque", str(torque)], check=True, capture_output=True, text=True)
    m = json.loads(out.stdout)["modes"]["mesh_mean"]
    return {mode["dominant_coordinate"]: mode["damped_frequency_hz"] for mode in m}


def model_psd(config, torque, f, roughness, fs_internal):
    """The one-sided PSD [(m/s^2)^2/Hz] of x_p'' and x_g'' of the linear 3-DOF model (seed 000 eq
    14-16; M q'' + C q' + K q = v k_s e, v = (1, -1, 1) over (x_p, x_g, x)) under white mesh
    displacement e of variance roughness^2 held over 1 / fs_internal: S_e = 2 roughness^2 / fs
    sinc^2(f / fs). Masses, stiffnesses and damping from drivetrain_cli modes."""
    out = subprocess.run([os.path.join(bin_dir, "drivetrain_cli"), "modes", "--config", config,
                          "--torque", str(torque)], check=True, capture_output=True, text=True)
    j = json.loads(out.stdout)
    m, k, c = j["masses"], j["stiffness"], j["damping"]
    mass = np.diag([m["pinion_mass"], m["gear_mass"], m["equivalent_mass"]])
    v = np.array([1.0, -1.0, 1.0])
    stiff = k["mesh_mean"] * np.outer(v, v) + np.diag([k["pinion_bearing"], k["gear_bearing"], 0])
    damp = c["mesh"] * np.outer(v, v) + np.diag([c["pinion_bearing"], c["gear_bearing"], 0])
    s_e = 2.0 * roughness**2 / fs_internal * np.sinc(f / fs_internal)**4
    psd = np.zeros((len(f), 2))
    for i, fi in enumerate(f):
        w = 2.0 * np.pi * fi
        q = np.linalg.solve(stiff - w * w * mass + 1j * w * damp, v * k["mesh_mean"])
        psd[i] = np.abs(w * w * q[:2])**2 * s_e[i]
    return psd


def peak(f, p, lo, hi, mesh_hz):
    """The frequency of the largest PSD in [lo, hi] Hz after smoothing over 9 bins, with the bins
    within 2 of a mesh harmonic (the deterministic lines) bridged by the neighbours' level."""
    q = p.copy()
    df = f[1] - f[0]
    near = np.abs(f / mesh_hz - np.round(f / mesh_hz)) * mesh_hz <= 2.0 * df
    idx = np.arange(len(f))
    q[near] = np.interp(idx[near], idx[~near], p[~near])
    q = np.convolve(q, np.ones(9) / 9.0, mode="same")
    band = (f >= lo) & (f <= hi)
    return f[band][np.argmax(q[band])]


# 1. Blocks and the replay.
rate, block = 51200.0, 1024
bag = os.path.join(work, "ripple.bag")
summary = rig_sim(bag, "--scenario", "torque_ripple", "--duration", "2")
blocks = read_blocks(bag)
check(summary.get("vibration") == len(blocks) == 100, f"100 blocks of 2 s ({len(blocks)})")
check(all(m.sample_rate == rate and len(m.data) == 2 * block for m, _ in blocks),
      "every block at 51200 Hz with 1024 samples of two channels")
check(all(list(m.channels) == ["pinion_bearing", "gear_bearing"] for m, _ in blocks),
      "channels pinion_bearing, gear_bearing")
stamps_ok = all(
    m.header.seq == i and abs(m.header.stamp.to_nsec() - round((EPOCH + i * block / rate) * 1e9)) <= 1
    and abs(t.to_nsec() - round((EPOCH + (i + 1) * block / rate) * 1e9)) <= 1
    for i, (m, t) in enumerate(blocks))
check(stamps_ok, "stamps at the first sample, contiguous; seq counting; recorded when complete")
check(bool(np.all(np.isfinite(samples(blocks)))), "finite samples")
report = os.path.join(work, "replay")
subprocess.run([os.path.join(bin_dir, "drivetrain_replay"), "--bag", bag, "--config", seed_yaml,
                "--vibration-topic", "/vibration", "--report", report], check=True,
               capture_output=True)
counters = json.load(open(os.path.join(report, "summary.json")))["counters"]
check(counters["accepted_vibration"] == 100 and counters["vibration_gaps"] == 0
      and counters["rejected_vibration"] == 0,
      f"replay accepts every block, no gap ({counters['accepted_vibration']}, "
      f"{counters['vibration_gaps']})")
plain = os.path.join(work, "ripple_plain.bag")
rig_sim(plain, "--scenario", "torque_ripple", "--duration", "2", "--vibration-rate", "0")
with rosbag.Bag(bag) as a, rosbag.Bag(plain) as b:
    check("/vibration" not in b.get_type_and_topic_info().topics, "--vibration-rate 0: no topic")
    ra = [(tp, m, t) for tp, m, t in a.read_messages(raw=True) if tp != "/vibration"]
    rb = list(b.read_messages(raw=True))
    check(len(ra) == len(rb) and all(x[0] == y[0] and x[1][1] == y[1][1] and x[2] == y[2]
                                     for x, y in zip(ra, rb)),
          f"the other topics' messages unchanged by the vibration ({len(ra)} messages)")

# 2. Physics: 10 s at the constant dynamics.speed_rpm (1000 rpm: mesh frequency 20 x 1000 / 60).
scaled_yaml = os.path.join(work, "pinion_scale_0.8.yaml")
with open(seed_yaml) as f:
    text = f.read().replace("file: ../bearings/",
                            "file: " + os.path.join(src, "config/bearings") + "/")
text = text.replace("  - name: pinion_bearing\n",
                    "  - name: pinion_bearing\n    stiffness_scale: 0.8\n", 1)
with open(scaled_yaml, "w") as f:
    f.write(text)
mesh_hz = 20 * 1000.0 / 60.0
peaks = {}
for name, config in (("seed", seed_yaml), ("pinion 0.8", scaled_yaml)):
    truth = modes(config, 0.1)
    path = os.path.join(work, name.replace(" ", "_") + ".bag")
    rig_sim(path, "--scenario", "torque_ripple", "--duration", "10", "--vibration-seed", "3", config=config)
    x = samples(read_blocks(path))
    found = {}
    for c, coord in ((0, "x_p"), (1, "x_g")):
        f, p = welch(x[:, c], rate)
        if c == 0:
            theory = model_psd(config, 0.1, f, 1e-7, 8 * rate) + 2.0 * 0.005**2 / rate
        # Around the two modes (0.9 x the gear's to 1.1 x the pinion's), away from the mesh lines,
        # the spectrum is the model's (Welch's scatter: 249 averages, about 6 % per bin; the held
        # input's folded direct term, a few % at 8 x oversampling).
        df = f[1] - f[0]
        keep = ((f >= 0.9 * truth["x_g"]) & (f <= 1.1 * truth["x_p"])
                & (np.abs(f / mesh_hz - np.round(f / mesh_hz)) * mesh_hz > 3.0 * df))
        ratio = p[keep] / theory[keep, c]
        check(abs(np.mean(ratio) - 1.0) < 0.1 and np.median(np.abs(ratio - 1.0)) < 0.1,
              f"{name}: {coord}'' spectrum around the modes / the linear model's: mean "
              f"{np.mean(ratio):.3f}, median deviation {np.median(np.abs(ratio - 1.0)):.3f}")
        found[coord] = peak(f, p, 0.85 * truth[coord], 1.15 * truth[coord], mesh_hz)
        err = found[coord] / truth[coord] - 1.0
        check(abs(err) < 0.01, f"{name}: {coord}'' peak {found[coord]:.0f} Hz, modal analysis "
              f"{truth[coord]:.0f} Hz ({100 * err:+.2f} %)")
    peaks[name] = (truth, found)
(t0, f0), (t1, f1) = peaks["seed"], peaks["pinion 0.8"]
check(t1["x_p"] < 0.95 * t0["x_p"] and f1["x_p"] < 0.95 * f0["x_p"],
      f"pinion 0.8: the pinion-shaft peak moves {f0['x_p']:.0f} -> {f1['x_p']:.0f} Hz "
      f"(predicted {t0['x_p']:.0f} -> {t1['x_p']:.0f})")
check(abs(f1["x_g"] / f0["x_g"] - 1.0) < 0.01,
      f"pinion 0.8: the gear-shaft peak stays ({f0['x_g']:.0f} -> {f1['x_g']:.0f} Hz)")

# 3. Anti-alias: the stop band holds the sensor-noise floor.
sigma = 0.005  # the default --vibration-noise [m/s^2]
x = samples(read_blocks(os.path.join(work, "seed.bag")))
quiet = os.path.join(work, "quiet.bag")
rig_sim(quiet, "--scenario", "torque_ripple", "--duration", "4", "--vibration-noise", "0")
xq = samples(read_blocks(quiet))
floor = 2.0 * sigma**2 / rate
for c in range(2):
    f, p = welch(x[:, c], rate)
    top = np.mean(p[f >= 0.46 * rate])
    mid = np.mean(p[(f >= 0.2 * rate) & (f <= 0.3 * rate)])
    check(abs(top / floor - 1.0) < 0.1 and mid > 1e4 * floor,
          f"channel {c}: PSD above 0.46 x rate {top:.3e} = noise floor {floor:.3e} within 10 %; "
          f"0.2-0.3 x rate {mid:.3e}")
    f, p = welch(xq[:, c], rate)
    top = np.mean(p[f >= 0.46 * rate])
    mid = np.mean(p[(f >= 0.2 * rate) & (f <= 0.3 * rate)])
    check(top < 1e-8 * mid, f"channel {c}, no sensor noise: stop band {10 * math.log10(top / mid):.0f}"
          " dB below 0.2-0.3 x rate")

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all vibration checks passed")
