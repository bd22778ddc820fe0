#!/usr/bin/python3
"""Report of a stiffness-estimator run from a bag of its outputs (drivetrain_replay --out, or
`rosbag record` of a live run): transmission error, its per-mesh-period statistics, stiffness and
resonance against time, as PNG plots plus report.md with the key figures; with INPUT_BAG's encoders
the TE order spectrum and the Campbell diagram (beside INPUT_BAG's accelerometers' spectrogram), and
from the modal identification's CSV files in CSV_DIR (drivetrain_replay's --csv; REPORT_DIR/csv
without it) the stabilisation diagram and its table (docs/tools.md "--report").

usage: plot_replay.py OUTPUT_BAG REPORT_DIR [INPUT_BAG [CSV_DIR]]
Times are seconds since the first output stamp; SI units (TE in m shown in um).
drivetrain_replay writes REPORT_DIR/summary.json and the top of REPORT_DIR/report.md (status, inputs,
calibration, output counts) before it runs this script, which then appends its figures. Without a
replay's summary (a live run's `rosbag record`) it writes the whole report.md. A run without
outputs (no torque accepted, or damage before the first) gets a note instead of figures."""
import json
import math
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: E402
    import numpy as np  # noqa: E402
    import rosbag  # noqa: E402
except ImportError as e:
    sys.exit("plot_replay.py: %s: install python3-matplotlib, python3-numpy and python3-rosbag, or skip the plots "
             "(drivetrain_replay --no-plots)" % e)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import modal_plots  # noqa: E402
import motion_analysis  # noqa: E402
import vibration_analysis  # noqa: E402


def read(bag_path):
    te, st, res, mp = [], [], [], []
    with rosbag.Bag(bag_path) as bag:
        for topic, m, _ in bag.read_messages(topics=["/transmission_error", "/stiffness", "/resonance",
                                                     "/mesh_period_stats"]):
            t = m.header.stamp.to_sec()
            if topic == "/mesh_period_stats":
                # Placed at the middle of the block it describes.
                mp.append((t - 0.5 * m.duration, m.te_mean, m.te_rms, m.mesh_force_mean, m.mesh_force_rms,
                           m.mesh_frequency, m.periods))
            elif topic == "/transmission_error":
                te.append((t, m.dynamic_te, m.static_te, m.mesh_force, m.mesh_phase))
            elif topic == "/stiffness":
                st.append((t, m.mesh_stiffness, m.mesh_stiffness_mean, [b.radial_stiffness for b in m.bearings],
                           [b.name for b in m.bearings], m.torque))
            else:
                res.append((t, list(m.frequencies_hz), list(m.dominant_coordinate), m.floquet_margin if m.floquet_valid else None))
    return te, st, res, mp


def finish(fig, axes, ylabels, title, path):
    """Labels a column of panels sharing the time axis and writes the PNG."""
    for a, label in zip(axes, ylabels):
        a.set_ylabel(label)
    axes[-1].set_xlabel("time [s]")
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def replay_summary(report):
    """drivetrain_replay's REPORT_DIR/summary.json; {} without one (e.g. a report of a live run's
    `rosbag record`)."""
    try:
        with open(os.path.join(report, "summary.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def replay_status(report):
    """drivetrain_replay's status ("ok" or "incomplete: ...") from REPORT_DIR/summary.json; None
    without one."""
    return replay_summary(report).get("status")


def encoder_settings(report):
    """The encoders' topic, the pinion's joint name and the pinion's tooth count the replay took
    (summary.json's "encoders"); the node's defaults (/joint_states, pinion, seed 000's z_p = 20)
    for a report without a replay's summary."""
    e = replay_summary(report).get("encoders") or {}
    topic = e.get("topic", "joint_states")
    return ("/" + topic.lstrip("/"), e.get("pinion_joint", "pinion"), int(e.get("pinion_teeth", 20)))


def write_header(f, status, source, out_bag):
    f.write("# Stiffness estimator report\n\n")
    if status and status != "ok":
        f.write("**Incomplete replay**: the bag could not be read to its end; the outputs and the figures below "
                "cover the messages before the damage only.\n\n`%s`\n\n" % status)
    f.write("Source: `%s`; outputs: `%s`.\n\n" % (source, out_bag))


def moving_mean(values, n):
    out, acc = [], 0.0
    for i, v in enumerate(values):
        acc += v
        if i >= n:
            acc -= values[i - n]
        out.append(acc / min(i + 1, n))
    return out


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out_bag, report = sys.argv[1], sys.argv[2]
    source = sys.argv[3] if len(sys.argv) > 3 else out_bag
    os.makedirs(report, exist_ok=True)
    status = replay_status(report)
    # A replay wrote the top of report.md: the figures are appended to it.
    appending = bool(replay_summary(report)) and os.path.exists(os.path.join(report, "report.md"))
    te, st, res, mp = read(out_bag)
    starts = [s[0][0] for s in (te, st, res) if s]
    if not starts:
        with open(os.path.join(report, "report.md"), "a" if appending else "w") as f:
            if not appending:
                write_header(f, status, source, out_bag)
            f.write("## Figures\n\nNo figures: there are no outputs (no /transmission_error, /stiffness or /resonance "
                    "in `%s`)%s.\n" % (out_bag, "; the inputs above say why" if appending else ""))
        return
    t0 = min(starts)

    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    if te:
        # The output grid samples the mesh period at a few phases only: dots for the samples, lines
        # for the mean over a sliding window of whole mesh periods' worth of samples.
        ts = [r[0] - t0 for r in te]
        for k, (col, label, scale, axis) in enumerate(((1, "dynamic TE", 1e6, 0), (2, "static TE", 1e6, 0), (3, "mesh force", 1.0, 1))):
            ys = [scale * r[col] for r in te]
            ax[axis].plot(ts, ys, ".", ms=1.5, color="C%d" % k, alpha=0.35)
            ax[axis].plot(ts, moving_mean(ys, 30), lw=1.4, color="C%d" % k, label=label + " (30-sample mean)")
        ax[0].legend(loc="upper right", fontsize=8)
        ax[1].legend(loc="upper right", fontsize=8)
    finish(fig, ax, ["mesh deflection [um]", "mesh force [N]"], "Predicted transmission error (3-DOF model)",
           os.path.join(report, "transmission_error.png"))

    # Per block of whole mesh periods (/mesh_period_stats): what the mesh does, where the 30-sample
    # mean above shows what the grid's few phases per period see.
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    if mp:
        ts = [r[0] - t0 for r in mp]
        for axis, (mean_col, rms_col, scale, label) in enumerate(((1, 2, 1e6, "dynamic TE"), (3, 4, 1.0, "mesh force"))):
            ax[axis].plot(ts, [scale * r[mean_col] for r in mp], lw=1.2, color="C0", label=label + ": per-period mean")
            ax[axis].plot(ts, [scale * r[rms_col] for r in mp], lw=1.0, color="C1", label=label + ": RMS about the mean")
            ax[axis].legend(loc="upper right", fontsize=8)
    finish(fig, ax, ["mesh deflection [um]", "mesh force [N]"], "Per mesh period (blocks of whole mesh periods)",
           os.path.join(report, "mesh_period_stats.png"))

    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    if st:
        for i, name in enumerate(st[0][4]):
            ax[0].plot([r[0] - t0 for r in st], [r[3][i] / 1e6 for r in st], lw=0.8, label=name)
        ax[1].plot([r[0] - t0 for r in st], [r[1] / 1e6 for r in st], lw=0.5, label="at the mesh phase")
        ax[1].plot([r[0] - t0 for r in st], [r[2] / 1e6 for r in st], lw=1.0, label="period mean")
        ax[0].legend(loc="best")
        ax[1].legend(loc="best")
    finish(fig, ax, ["bearing radial stiffness [N/um]", "composite mesh stiffness [N/um]"], "Stiffness estimates",
           os.path.join(report, "stiffness.png"))

    fig, ax = plt.subplots(figsize=(9, 4))
    if res:
        t_end = max(starts + [te[-1][0] if te else t0, st[-1][0] if st else t0])
        for k in range(len(res[0][1])):
            xs, ys = [], []
            for j, r in enumerate(res):  # a latched estimate holds until the next one
                t_next = res[j + 1][0] if j + 1 < len(res) else t_end
                xs += [r[0] - t0, t_next - t0]
                ys += [r[1][k] / 1e3, r[1][k] / 1e3]
            ax.plot(xs, ys, lw=1.2, label="mode %d (%s)" % (k + 1, res[-1][2][k]))
        ax.set_yscale("log")
        ax.legend(loc="best")
    finish(fig, [ax], ["natural frequency [kHz]"], "Resonance estimates", os.path.join(report, "resonance.png"))

    modal = modal_plots.ModalResults(sys.argv[4] if len(sys.argv) > 4 else os.path.join(report, "csv"))
    records, vibration_note = read_records(source) if source != out_bag else ([], "")
    motion_figures = (plot_motion(source, te, res, t0, report, modal, records, *encoder_settings(report))
                      if source != out_bag and te else [])
    if source != out_bag and not te:
        motion_figures = [(None, "", "No Campbell diagram or TE order spectrum: the replay made no transmission error "
                                     "samples (no dynamics).")]

    with open(os.path.join(report, "report.md"), "a" if appending else "w") as f:
        if appending:
            f.write("\n## Figures\n\n")
        else:
            write_header(f, status, source, out_bag)
        f.write("| quantity | value |\n|---|---|\n")
        f.write("| span of outputs | %.3f s |\n" % (max(r[0] for r in te + st) - t0 if te or st else 0.0))
        f.write("| transmission_error samples | %d |\n| stiffness messages | %d |\n| resonance updates | %d |\n"
                % (len(te), len(st), len(res)))
        if te:
            d = [r[1] for r in te]
            mean = sum(d) / len(d)
            rms = math.sqrt(sum((x - mean) ** 2 for x in d) / len(d))
            f.write("| dynamic TE mean / RMS about mean / peak-to-peak | %.4g / %.4g / %.4g um |\n"
                    % (1e6 * mean, 1e6 * rms, 1e6 * (max(d) - min(d))))
        if mp:
            f.write("| mesh period blocks / periods | %d / %d |\n" % (len(mp), sum(r[6] for r in mp)))
            f.write("| per-period dynamic TE mean / RMS, last block | %.4g / %.4g um |\n" % (1e6 * mp[-1][1], 1e6 * mp[-1][2]))
            f.write("| per-period mesh force mean / RMS, last block | %.4g / %.4g N at %.4g Hz |\n"
                    % (mp[-1][3], mp[-1][4], mp[-1][5]))
        if st:
            for i, name in enumerate(st[-1][4]):
                f.write("| %s radial stiffness, first / last | %.4g / %.4g N/um |\n"
                        % (name, st[0][3][i] / 1e6, st[-1][3][i] / 1e6))
        if res:
            f.write("| last resonance estimate | %s |\n" % ", ".join(
                "%.0f Hz (%s)" % (fr, dom) for fr, dom in zip(res[-1][1], res[-1][2])))
            if res[-1][3] is not None:
                f.write("| Floquet margin | %.3f |\n" % res[-1][3])
        f.write("\n![transmission error](transmission_error.png)\n\n![per mesh period](mesh_period_stats.png)\n\n"
                "![stiffness](stiffness.png)\n\n"
                "![resonance](resonance.png)\n")
        for name, caption, note in motion_figures + plot_modal(modal, records, t0, report) + (
                [(None, "", vibration_note)] if vibration_note else []):
            if name:
                f.write("\n![%s](%s)\n" % (caption, name))
            if note:
                f.write("\n%s\n" % note)


def read_records(input_bag):
    """The input bag's accelerometer records (vibration_analysis.read_vibration) and "", or [] and
    a note saying why they could not be read."""
    try:
        return vibration_analysis.read_vibration(input_bag)[1], ""
    except Exception as e:  # noqa: BLE001 - not a bag rosbag reads (a damaged input)
        return [], "No accelerometer spectra: the input bag could not be read (%s: %s)." % (type(e).__name__, e)


def plot_modal(modal, records, t0, report):
    """The stabilisation diagram of the last identification that matched a model mode (else the
    last one) and report.md's table of it, from the replay's modal_identification.csv and
    modal_poles.csv; a note instead when they are absent or empty."""
    if modal.identification is None or modal.poles is None:
        missing = [n for n, rows in ((modal_plots.IDENTIFICATION_FILE, modal.identification),
                                     (modal_plots.POLES_FILE, modal.poles)) if rows is None]
        return [(None, "", "No stabilisation diagram or modal identification table: the replay wrote no %s (no "
                           "modal identification: no accelerometers, or a replay or bag older than the stage)."
                 % " or ".join("`%s`" % n for n in missing))]
    stamp = modal.chosen_stamp()
    if stamp is None:
        return [(None, "", "No stabilisation diagram: `%s` has no identification." % modal_plots.IDENTIFICATION_FILE)]
    note = modal_plots.stabilisation_figure(os.path.join(report, "stabilisation.png"), modal, stamp, records, t0)
    return [(None, "", modal_plots.identification_table(modal, stamp, t0)),
            ("stabilisation.png", "stabilisation diagram", note)]


def save(fig, report, name, caption, note=""):
    """Writes the figure as REPORT/name; returns (name, caption, note) for report.md."""
    fig.tight_layout()
    fig.savefig(os.path.join(report, name), dpi=110)
    plt.close(fig)
    return name, caption, note


def plot_motion(input_bag, te, res, t0, report, modal, records, topic="/joint_states", joint="pinion", z_p=20):
    """With the rig's encoders in the input bag (`topic`, the pinion's `joint`): the TE order
    spectrum (angle-domain resampling) and the Campbell diagram (modal_plots.campbell_figure: the
    TE's mesh-order amplitudes against the measured speed, by regression on the mesh phase, with
    the mesh orders of the pinion's z_p teeth, the predicted modes, the identified poles of `modal`
    and the spectrogram of the accelerometer `records` beside it). Returns the (file, caption,
    note) triples written, and (None, "", note) for a figure left out, saying why."""
    def left_out(why):
        return [(None, "", "No Campbell diagram or TE order spectrum: %s." % why)]
    try:
        enc_t, enc_angle, enc_speed = motion_analysis.read_encoder(input_bag, joint, topic)
    except Exception as e:  # noqa: BLE001 - not a bag rosbag reads (a damaged input)
        return left_out("the encoders could not be read from the input bag (%s: %s)" % (type(e).__name__, e))
    if len(enc_t) < 10:
        return left_out("%d readings of joint '%s' on %s in the input bag (10 needed)" % (len(enc_t), joint, topic))
    te_t = np.array([r[0] for r in te])
    dyn = np.array([r[1] for r in te])
    out = []
    spec = motion_analysis.order_spectrum(te_t, dyn, enc_t, enc_angle)
    if spec is not None:
        orders, amp = spec
        fig, ax = plt.subplots(figsize=(9, 4))
        ax.semilogy(orders, 1e6 * amp + 1e-12, lw=0.8)
        for k in range(1, 5):
            ax.axvline(k * z_p, color="grey", lw=0.6, ls="--")
        ax.set_xlim(0, 5 * z_p)
        ax.set_xlabel("order [cycles per pinion revolution]; dashed: mesh orders 1-4 (z_p = %d)" % z_p)
        ax.set_ylabel("dynamic TE amplitude [um]")
        ax.set_title("Transmission error order spectrum (angle-domain resampling)")
        out.append(save(fig, report, "te_order_spectrum.png", "TE order spectrum"))
    else:
        turns = abs(enc_angle[-1] - enc_angle[0]) / (2 * np.pi)
        out.append((None, "", "No TE order spectrum: the pinion turns %.2f revolutions over the encoder readings; "
                              "the angle-domain resampling needs 4 revolutions in one direction." % turns))
    if not (len(te_t) > 1 and te_t[-1] - te_t[0] > 0.5):
        out.append((None, "", "No Campbell diagram: the transmission error spans %.3f s (more than 0.5 s needed)."
                              % (te_t[-1] - te_t[0] if len(te_t) else 0.0)))
        return out
    speed = np.abs(np.interp(te_t, enc_t, enc_speed)) * 60.0 / (2 * np.pi)
    if not np.ptp(speed) > 1.0:
        out.append((None, "", "No Campbell diagram: the encoders' speed spans %.2f rpm over the transmission error "
                              "(it needs more than 1 rpm: a diagram against speed needs the speed to change)."
                              % np.ptp(speed)))
        return out
    def omega_at(t):
        return np.interp(t, enc_t, enc_speed)
    # The mesh orders up to the top of the diagram in each window (at most modal_plots.MAX_ORDER).
    top, _ = modal_plots.band_top(res, modal, records, 1.1 * 4 * z_p * speed.max() / 60.0)
    tracks = motion_analysis.mesh_order_amplitudes(
        te_t, dyn, np.array([r[4] for r in te]), max_order=modal_plots.MAX_ORDER,
        orders_in_window=lambda t: top / max(1e-9, z_p * abs(omega_at(t)) / (2 * np.pi)))
    note = modal_plots.campbell_figure(os.path.join(report, "campbell.png"), tracks, z_p, omega_at, res, te_t[-1],
                                       modal, records, t0)
    out.append(("campbell.png", "Campbell diagram", note))
    return out


if __name__ == "__main__":
    main()
