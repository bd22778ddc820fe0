"""One bag's task: the full `drivetrain_replay` with calibration, and the bag's row from its outputs.

Runs on a dask worker (or in-process for --serial). The replay writes into a scratch directory
beside the bag's final one, renamed into place when it is complete, so a worker killed mid-bag
leaves no half-written report where the retried task will put its own; its replay process dies
with it (PR_SET_PDEATHSIG), so it cannot write on after the retry started.
"""

import ctypes
import json
import os
import shutil
import signal
import subprocess
import uuid

# The calibrated parameters of msg/Calibration.msg, in its order (docs/calibration.md).
CALIBRATED = ("mesh_stiffness_scale", "pinion_bearing_scale", "gear_bearing_scale", "preload_torque", "te_offset")
MODES = 3  # natural frequencies of the 3-DOF model (seed 000 §3)
# The model's coordinates that name its modes by the one holding most of a mode's energy
# (msg/PredictedMode.msg `dominant`; docs/model.md): pinion and gear transverse, mesh.
MODAL_COORDINATES = ("x_p", "x_g", "x")

_PR_SET_PDEATHSIG = 1

# What each bag's report keeps (--bag-outputs report, the default): in csv/ and outputs.bag the
# small topics (a row per calibration window, resonance change, spectrum or block of mesh
# periods), which a reader of the report needs, and with plots also, in outputs.bag alone, the
# topics plot_replay.py reads from it. Not the per-reading measured_te (5 kHz) nor the 1 kHz
# stiffness and TE as CSV: those are 2.3x the input bag, and formatting them took the replay from
# 1.0 to 1.15 cores, which two workers on two cores could not give (docs/campaign.md, Figures).
# --bag-outputs all keeps every topic in both.
REPORT_TOPICS = ("te_spectrum", "resonance", "calibration", "mesh_period_stats")
PLOT_TOPICS = ("transmission_error", "stiffness", "resonance", "mesh_period_stats")
BAG_OUTPUTS = ("report", "all")


def _die_with_parent():
    """In the child before exec: SIGKILL when the worker that started it dies (Linux)."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except OSError:
        pass  # not Linux: a lost worker's replay then runs to its end, into its own scratch directory


def report_topics(plots, bag_outputs):
    """drivetrain_replay's --topics (outputs.bag) and --csv-topics (csv/) for a bag's report: "all",
    or comma-separated names (summary.json lists the same names in the message order)."""
    if bag_outputs == "all":
        return "all", "all"
    csv_names = set(REPORT_TOPICS)
    bag_names = csv_names | (set(PLOT_TOPICS) if plots else set())
    return ",".join(sorted(bag_names)), ",".join(sorted(csv_names))


def replay_command(job, out_dir):
    plots = job.get("plots", True)
    bag_topics, csv_topics = report_topics(plots, job.get("bag_outputs", "report"))
    cmd = [job["replay"], "--bag", job["bag"], "--config", job["config"], "--report", out_dir,
           "--calibrate", os.path.join(out_dir, "calibrated_gearbox.yaml"),
           "--topics", bag_topics, "--csv-topics", csv_topics]
    if job.get("params"):
        cmd += ["--params", job["params"]]
    if not plots:
        cmd.append("--no-plots")
    return cmd


def run_replay(job):
    """Replays job['bag'] into job['out_dir'] (replaced whole) and returns its row (table.COLUMNS)."""
    final = job["out_dir"]
    scratch = f"{final}.part-{uuid.uuid4().hex[:8]}"
    os.makedirs(scratch)
    # dask's nanny gives its workers MALLOC_TRIM_THRESHOLD_=65536 (distributed.nanny.pre-spawn-environ),
    # for the worker's own Python heap; inherited, it makes glibc hand memory back after nearly
    # every free in the replay too (measured: a 60 s load_sweep bag 5.79 -> 6.04 s). The replay is
    # a separate program with its own allocation pattern: it gets the environment without it.
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
    proc = subprocess.run(replay_command(job, scratch), capture_output=True, text=True, preexec_fn=_die_with_parent,
                          env=env)
    summary_path = os.path.join(scratch, "summary.json")
    summary = None
    if os.path.exists(summary_path):
        with open(summary_path) as f:
            summary = json.load(f)
    if os.path.isdir(final):
        shutil.rmtree(final)
    os.replace(scratch, final)
    return bag_row(job, proc.returncode, proc.stderr, summary, final)


def _stderr_reason(stderr):
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    reason = lines[-1] if lines else "no message"
    return reason[len("drivetrain_replay: "):] if reason.startswith("drivetrain_replay: ") else reason


def bag_row(job, returncode, stderr, summary, out_dir):
    """The bag's campaign row from the replay's exit code, stderr and summary.json
    (docs/replay_exit_codes.md): refused without a summary, else its status, counts, ranges,
    per-mesh-period TE statistics, final modal frequencies and calibration."""
    row = {"bag": job["bag"], "sha256": job["sha256"], "report": os.path.relpath(out_dir, job["campaign_dir"])}
    if summary is None:
        row["status"] = f"refused: {_stderr_reason(stderr)} (exit {returncode})"
        return row
    row["status"] = summary["status"]
    row["start"] = summary.get("start")
    row["duration"] = summary.get("span_s")
    counters = summary.get("counters", {})
    for kind in ("accepted", "rejected", "dropped"):
        row[kind] = sum(int(v) for k, v in counters.items() if k.startswith(kind + "_"))
    row["wrong_type"] = summary.get("wrong_type", 0)
    row.update(period_statistics(summary))
    frequencies = summary.get("final_resonance_hz") or []
    for i in range(MODES):
        row[f"natural_frequency_{i + 1}"] = frequencies[i] if i < len(frequencies) else None
    row.update(modal_columns(summary))
    calibration = summary.get("calibration", {})
    row["calibration_updates"] = calibration.get("updates")
    row["modal_updates"] = calibration.get("modal_updates")
    row["modal_gated"] = calibration.get("modal_gated")
    for name in CALIBRATED:
        for suffix in ("", "_std", "_identified"):
            row[name + suffix] = calibration.get(name + suffix)
    row["calibration_status"] = summary.get("calibrate_error") or calibration.get("status")
    return row


def modal_columns(summary):
    """The accelerometers' modal identification over the bag, from summary.json's "modal"
    (src/tools/replay/modal_totals.hpp): modal_identifications, the records identified; per model mode,
    named by its dominant coordinate, the last identified frequency and its standard deviation
    [Hz], empty when no record identified it (or, for _std, when the record did not compute one)."""
    modal = summary.get("modal") or {}
    row = {"modal_identifications": modal.get("records")}
    modes = modal.get("modes") or {}
    for name in MODAL_COORDINATES:
        mode = modes.get(name) or {}
        row[f"modal_frequency_{name}"] = mode.get("frequency")
        row[f"modal_frequency_{name}_std"] = mode.get("frequency_std")
    return row


PERIOD_KEYS = ("speed_min", "speed_max", "torque_min", "torque_max", "te_rms", "te_peak_to_peak", "mesh_force_mean")


def period_statistics(summary):
    """Speed and torque ranges and TE figures over the bag's per-mesh-period blocks
    (msg/MeshPeriodStats.msg), as drivetrain_replay sums them into summary.json's "mesh_periods"
    (src/tools/replay/mesh_period_totals.hpp): pinion speed = 2 pi f_mesh / z_p [rad/s]; torque = the
    block's mean held pinion torque [N*m]; te_rms = RMS about each block's mean, combined over
    blocks by time [m]; te_peak_to_peak = the largest block's [m]; mesh_force_mean = time-weighted
    [N]. Empty when the bag gave no block."""
    totals = summary.get("mesh_periods") or {}
    return {k: totals.get(k) for k in PERIOD_KEYS}
