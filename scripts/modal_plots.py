"""The replay report's modal figures (plot_replay.py):

- campbell_figure: the Campbell diagram, alias-free (the TE's mesh-order amplitudes from the
  regression on the mesh phase, placed at k z_p n / 60), with the mesh orders, the predicted modes
  and the identified poles (±σ) against the speed, beside the accelerometers' spectrogram;
- stabilisation_figure: one identification's poles against the model order, beside the
  accelerometers' averaged PSD;
- identification_table: report.md's table of one identification.
The identification comes from the replay's modal_identification.csv and modal_poles.csv
(docs/vibration.md "Identification"); without them (a replay without the stage, an older bag)
the figures leave the poles out and say so. SI units; speeds shown in rpm."""
import csv
import os

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.gridspec import GridSpec
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

import vibration_analysis

IDENTIFICATION_FILE = "modal_identification.csv"
POLES_FILE = "modal_poles.csv"
TEXT_FIELDS = ("status", "dominant")
# Above this the Campbell diagram's frequency axis does not go without accelerometers to say
# where their band ends: half the default 51.2 kHz rate (docs/vibration.md "Input").
DEFAULT_BAND_TOP = 25600.0
# Mesh orders fitted per window of the Campbell diagram (at low speed the band holds many).
MAX_ORDER = 40
# Mesh orders drawn over the accelerometers' spectrogram (more hide it at low speed).
SPECTROGRAM_ORDERS = 8


def read_csv(path):
    """The rows of a CSV file with a header line as dicts: the TEXT_FIELDS as strings, every other
    cell a float, an empty cell None. None if the file does not exist."""
    if not os.path.exists(path):
        return None
    rows = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            rows.append({k: (v if k in TEXT_FIELDS else (float(v) if v not in ("", None) else None))
                         for k, v in row.items()})
    return rows


class ModalResults:
    """modal_identification.csv and modal_poles.csv of a replay's CSV directory; either list is
    None when its file is absent."""

    def __init__(self, csv_dir):
        self.identification = read_csv(os.path.join(csv_dir, IDENTIFICATION_FILE))
        self.poles = read_csv(os.path.join(csv_dir, POLES_FILE))

    def stamps(self):
        """The identifications' stamps [s], ascending."""
        return sorted({r["stamp"] for r in self.identification or []})

    def rows_at(self, stamp):
        return [r for r in self.identification or [] if r["stamp"] == stamp]

    def poles_at(self, stamp):
        return [p for p in self.poles or [] if p["stamp"] == stamp]

    def chosen_stamp(self):
        """The last identification that matched a model mode; else the last one; None without one."""
        stamps = self.stamps()
        matched = [s for s in stamps if any(r["status"] == "identified" for r in self.rows_at(s))]
        return (matched or stamps or [None])[-1]


def mode_colour(model_mode):
    """One colour per model mode (C0, C1, C2), black for a mode matched to none."""
    return "C%d" % int(model_mode) if model_mode is not None and model_mode >= 0 else "k"


def rpm(omega):
    return np.asarray(omega) * 60.0 / (2 * np.pi)


def band_top(resonance, modal, records, mesh_top):
    """[Hz] the Campbell diagram's top: 1.15 x the highest predicted or identified mode inside the
    accelerometers' band (their Nyquist frequency, else DEFAULT_BAND_TOP), at least mesh_top.
    Returns (top, the predicted modes above the band [Hz])."""
    ceiling = max([r.sample_rate / 2 for r in records] + [r["sample_rate"] / 2 for r in modal.identification or []
                                                          if r["sample_rate"]] or [DEFAULT_BAND_TOP])
    freqs = [f for r in resonance for f in r[1]]
    for r in modal.identification or []:
        freqs += [r[k] for k in ("predicted_frequency", "frequency") if r[k] is not None and r["status"] != "above Nyquist"]
    inside = [f for f in freqs if f <= ceiling]
    above = sorted({round(f) for f in freqs if f > ceiling})
    return max([mesh_top] + [1.15 * f for f in inside]), above


def draw_identified(ax, rows, x_of):
    """Identified modes as points with ±σ bars at x_of(row), one colour per model mode (hollow: no
    model mode)."""
    for r in rows:
        if r["frequency"] is None:
            continue
        c = mode_colour(r["model_mode"])
        ax.errorbar(x_of(r), r["frequency"], yerr=r["frequency_std"] or 0.0, fmt="o", ms=5, color=c,
                    mfc=c if r["status"] == "identified" else "none", mec="k" if c != "k" else c, capsize=3,
                    elinewidth=1.2, zorder=5)


def draw_predicted_bands(ax, rows):
    """Each model mode's predicted frequency and band (predicted_low..predicted_high) against the
    speed of the identifications' records."""
    for m in sorted({r["model_mode"] for r in rows if r["model_mode"] is not None and r["model_mode"] >= 0}):
        pts = sorted((rpm(r["pinion_speed"]), r["predicted_frequency"], r["predicted_low"], r["predicted_high"])
                     for r in rows if r["model_mode"] == m and r["predicted_frequency"] is not None
                     and r["pinion_speed"] is not None and r["status"] != "above Nyquist")
        if not pts:
            continue
        n, f, lo, hi = (np.array(v, dtype=float) for v in zip(*pts))
        lo, hi = np.where(np.isnan(lo), f, lo), np.where(np.isnan(hi), f, hi)
        if len(pts) > 1:
            ax.fill_between(n, lo, hi, color=mode_colour(m), alpha=0.15, lw=0, zorder=1)
            ax.plot(n, f, ":", color=mode_colour(m), lw=1.2, zorder=2)
        else:
            ax.errorbar(n, f, yerr=[f - lo, hi - f], fmt="_", color=mode_colour(m), alpha=0.4, elinewidth=6, zorder=1)


def nan_none(v):
    return np.nan if v is None else v


def campbell_panel(ax, tracks, z_p, omega_at, resonance, t_end, modal, top):
    """The Campbell diagram on ax: mesh-order amplitudes of the TE (colour, log) at k z_p n / 60,
    the mesh orders as lines, the predicted modes (resonance estimates while they held, red; the
    identification's predicted bands) and the identified poles ±σ. Returns the colour mapping."""
    t_mid, amp = tracks
    w = omega_at(t_mid)
    f_mesh = z_p * np.abs(w) / (2 * np.pi)
    k = np.arange(1, amp.shape[1] + 1)
    x = np.repeat(rpm(w)[:, None], len(k), axis=1)
    y = f_mesh[:, None] * k[None, :]
    keep = np.isfinite(amp) & (amp > 0) & (y <= top)
    level = np.log10(amp[keep])
    sc = ax.scatter(x[keep], y[keep], c=level, s=5, marker="s", lw=0, cmap="viridis",
                    vmin=np.percentile(level, 5) if level.size else None, zorder=3)
    n = np.linspace(rpm(w).min(), rpm(w).max(), 200)
    for order in k:
        f = order * z_p * np.abs(n) / 60.0
        if f.min() > top:
            break
        ax.plot(n, f, color="0.6", lw=0.5, zorder=2)
        if order <= 6:
            j = int(np.argmin(np.abs(f - top))) if f.max() > top else len(n) - 1
            ax.text(n[j], min(f[j], top), " %d" % order, fontsize=7, color="0.35", va="top")
    # Each resonance estimate from its stamp to the next one's, at the encoders' speed over that time.
    for j, r in enumerate(resonance):
        t_next = resonance[j + 1][0] if j + 1 < len(resonance) else t_end
        if t_next < r[0]:
            continue
        held = rpm(omega_at(np.linspace(r[0], t_next, 20)))
        for fr in r[1]:
            if fr <= top:
                ax.plot(held, np.full_like(held, fr), "r-", lw=1.0, zorder=4)
    rows = modal.identification or []
    draw_predicted_bands(ax, rows)
    draw_identified(ax, [r for r in rows if r["pinion_speed"] is not None], lambda r: rpm(r["pinion_speed"]))
    ax.set_ylim(0, top)
    ax.set_xlabel("pinion speed [rpm] (encoders)")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title("Campbell diagram: TE mesh-order amplitudes (colour), mesh orders (grey),\n"
                 "predicted modes (red; bands of the identification), identified poles ±σ")
    handles = [Line2D([], [], color="0.6", lw=0.8, label="mesh orders k z_p n / 60"),
               Line2D([], [], color="r", lw=1.0, label="resonance estimates")]
    if rows:
        handles += [Patch(color="0.5", alpha=0.3, label="predicted band (identification)"),
                    Line2D([], [], marker="o", color="k", ls="", label="identified ±σ (hollow: no model mode)")]
    ax.legend(handles=handles, loc="upper left", fontsize=7)
    return sc


def spectrogram_panels(fig, axes, records, z_p, omega_at, resonance, t_end, modal, t0):
    """The accelerometers' spectrogram, one panel per channel (the first two) up to the Nyquist
    frequency, against time since t0, with the mesh orders (white), the resonance estimates (red)
    and the identified poles ±σ at the middle of their record."""
    rows = modal.identification or []
    for c, ax in enumerate(axes):
        images = [vibration_analysis.spectrogram(r, c) for r in records if c < r.data.shape[1]]
        images = [i for i in images if i is not None]
        if not images:
            continue
        levels = np.concatenate([10 * np.log10(i[2].ravel() + 1e-30) for i in images])
        lo, hi = np.percentile(levels, 5), levels.max()
        for t, f, p in images:
            mesh = ax.pcolormesh(t - t0, f, 10 * np.log10(p + 1e-30), shading="nearest", cmap="magma", vmin=lo, vmax=hi,
                                 rasterized=True)
        nyquist = max(r.sample_rate / 2 for r in records)
        ts = np.linspace(min(r.start for r in records), max(r.end for r in records), 400)
        f_mesh = z_p * np.abs(omega_at(ts)) / (2 * np.pi)
        for order in range(1, SPECTROGRAM_ORDERS + 1):
            if (order * f_mesh).min() > nyquist:
                break
            ax.plot(ts - t0, order * f_mesh, color="w", lw=0.5, alpha=0.6)
        for j, r in enumerate(resonance):
            t_next = resonance[j + 1][0] if j + 1 < len(resonance) else t_end
            for fr in r[1]:
                if fr <= nyquist and t_next >= r[0]:
                    ax.plot([r[0] - t0, t_next - t0], [fr, fr], "r--", lw=0.9)
        draw_identified(ax, [r for r in rows if r["record_start"] is not None],
                        lambda r: r["record_start"] + 0.5 * nan_none(r["record_duration"]) - t0)
        ax.set_ylim(0, nyquist)
        ax.set_xlim(ts[0] - t0, ts[-1] - t0)
        ax.set_ylabel("frequency [Hz]")
        ax.set_title("accelerometer '%s': PSD [dB re 1 (m/s²)²/Hz]" % records[0].channels[c], fontsize=9)
        fig.colorbar(mesh, ax=ax, pad=0.01)
    axes[-1].set_xlabel("time [s]; white: mesh orders 1-%d, red: resonance estimates, points: identified ±σ"
                        % SPECTROGRAM_ORDERS)


def campbell_figure(path, tracks, z_p, omega_at, resonance, t_end, modal, records, t0):
    """Writes the Campbell diagram, with the accelerometers' spectrogram beside it when there are
    records, to path. tracks: (window mid-times [s], amplitudes [m]: windows x orders) from
    motion_analysis.mesh_order_amplitudes (fitted up to band_top); omega_at(t) -> pinion speed
    [rad/s]; resonance: [(stamp [s], frequencies [Hz], dominant coordinates)]. Returns the notes
    for report.md."""
    w = omega_at(tracks[0])
    top, above = band_top(resonance, modal, records, 1.1 * 4 * z_p * np.abs(w).max() / (2 * np.pi))
    channels = min(2, max([r.data.shape[1] for r in records] or [0]))
    if channels:
        fig = plt.figure(figsize=(17, 6.5))
        grid = GridSpec(channels, 2, figure=fig, width_ratios=[1.2, 1.0])
        ax = fig.add_subplot(grid[:, 0])
        spec_axes = [fig.add_subplot(grid[0, 1])]
        spec_axes += [fig.add_subplot(grid[c, 1], sharex=spec_axes[0]) for c in range(1, channels)]
    else:
        fig, ax = plt.subplots(figsize=(9, 5.5))
    sc = campbell_panel(ax, tracks, z_p, omega_at, resonance, t_end, modal, top)
    fig.colorbar(sc, ax=ax, pad=0.01).set_label("log10 TE mesh-order amplitude [m]")
    if channels:
        spectrogram_panels(fig, spec_axes, records, z_p, omega_at, resonance, t_end, modal, t0)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    notes = []
    fitted = np.isfinite(tracks[1]).any(axis=1)
    if (~fitted).any():
        notes.append("%d of %d TE windows have no mesh-order amplitudes (their samples' mesh phases do not spread "
                     "over the period, e.g. sampling synchronous with the mesh)." % ((~fitted).sum(), len(fitted)))
    if above:
        notes.append("Predicted modes above the accelerometers' band, not drawn: %s Hz." % ", ".join("%d" % f for f in above))
    if modal.identification is None:
        notes.append("No identified poles: the replay wrote no `%s` (no modal identification: no accelerometers, "
                     "or a replay or bag older than the stage)." % IDENTIFICATION_FILE)
    if not records:
        notes.append("No accelerometer spectrogram: the input bag has no `%s` topic." % vibration_analysis.VIBRATION_TYPE)
    return " ".join(notes)


def stabilisation_figure(path, modal, stamp, records, t0):
    """Writes the stabilisation diagram of the identification at `stamp` [s] to path: its poles,
    frequency against model order (stable, not stable, inside a removed order band: distinct
    markers), the selected modes (solid vertical lines, ±σ shaded), the predicted modes (dotted,
    band shaded) and the accelerometers' averaged PSD over the identification's record on a second
    axis. Returns the caption's note."""
    rows, poles = modal.rows_at(stamp), modal.poles_at(stamp)
    fig, ax = plt.subplots(figsize=(11, 6))
    groups = (("stable", lambda p: p["stable"] == 1 and p["order_band"] != 1, dict(marker="o", ms=4, mfc="none", color="k")),
              ("not stable", lambda p: p["stable"] != 1 and p["order_band"] != 1, dict(marker="+", ms=5, color="0.55")),
              ("in a removed order band", lambda p: p["order_band"] == 1, dict(marker="x", ms=4, color="C1")))
    for label, test, style in groups:
        sel = [p for p in poles if test(p)]
        ax.plot([p["frequency"] for p in sel], [p["order"] for p in sel], ls="", label="%s (%d)" % (label, len(sel)), **style)
    for p in [p for p in poles if p["mode"] is not None and p["mode"] >= 0]:
        ax.plot(p["frequency"], p["order"], "o", ms=4, color="k", zorder=4)
    for r in rows:
        c = mode_colour(r["model_mode"])
        if r["predicted_frequency"] is not None and r["status"] != "above Nyquist":
            ax.axvline(r["predicted_frequency"], color=c, ls=":", lw=1.2)
            if r["predicted_low"] is not None and r["predicted_high"] is not None:
                ax.axvspan(r["predicted_low"], r["predicted_high"], color=c, alpha=0.07, lw=0)
        if r["frequency"] is not None:
            ax.axvline(r["frequency"], color=c, lw=1.5,
                       label="mode %d: %.1f ± %.1f Hz, ζ %.4f ± %.4f (%s)" % (
                           int(r["mode"]), r["frequency"], r["frequency_std"] or 0.0, nan_none(r["damping"]),
                           nan_none(r["damping_std"]), "model mode %d" % r["model_mode"]
                           if r["status"] == "identified" else "no model mode"))
            if r["frequency_std"]:
                ax.axvspan(r["frequency"] - r["frequency_std"], r["frequency"] + r["frequency_std"], color=c, alpha=0.25, lw=0)
    rate = next((r["sample_rate"] for r in rows if r["sample_rate"]), None)
    right = rate / 2 if rate else 1.05 * max([p["frequency"] for p in poles] or [1.0])
    ax.set_xlim(0, right)
    ax.set_xlabel("frequency [Hz]; dotted: predicted modes (band shaded), solid: selected modes (±σ shaded)")
    ax.set_ylabel("model order")
    note = ""
    first = rows[0] if rows else None
    psd = None
    if first is not None and first["record_start"] is not None and first["record_duration"]:
        psd = vibration_analysis.averaged_psd(records, first["record_start"], first["record_start"] + first["record_duration"])
    if psd is not None:
        f, p, names = psd
        ax2 = ax.twinx()
        for c in range(min(2, len(p))):
            ax2.semilogy(f, p[c], lw=0.7, color=("C4", "C9")[c], alpha=0.8, label="PSD %s" % names[c])
        ax2.set_ylabel("acceleration PSD [(m/s²)²/Hz] (record's Welch average)")
        ax2.legend(loc="upper right", fontsize=7)
    elif records:
        note = "No PSD beside the stabilisation diagram: the input bag's accelerometers do not cover the record."
    else:
        note = "No PSD beside the stabilisation diagram: no accelerometer records in an input bag."
    ax.legend(loc="upper left", fontsize=7)
    if first is not None:
        ax.set_title("Stabilisation diagram: identification at %.2f s (record %.2f-%.2f s, %.0f rpm, %.3g N·m)" % (
            stamp - t0, nan_none(first["record_start"]) - t0,
            nan_none(first["record_start"]) + nan_none(first["record_duration"]) - t0,
            rpm(nan_none(first["pinion_speed"])), nan_none(first["torque"])))
    else:
        ax.set_title("Stabilisation diagram: identification at %.2f s" % (stamp - t0))
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return note


def fmt(v, spec):
    return "" if v is None else spec % v


def identification_table(modal, stamp, t0):
    """report.md's table of the identification at `stamp`, one row per mode as the CSV has them,
    and how often each model mode was identified over all identifications."""
    out = ["| model mode | status | dominant | predicted [Hz] (band) | identified [Hz] ± σ | damping ± σ | MAC |",
           "|---|---|---|---|---|---|---|"]
    for r in modal.rows_at(stamp):
        band = "" if r["predicted_low"] is None else " (%.0f-%.0f)" % (r["predicted_low"], r["predicted_high"])
        out.append("| %s | %s%s | %s | %s%s | %s | %s | %s |" % (
            fmt(r["model_mode"], "%d") if r["model_mode"] is not None and r["model_mode"] >= 0 else "-",
            r["status"], " (unresolved)" if r["unresolved"] == 1 else "", r["dominant"] or "",
            fmt(r["predicted_frequency"], "%.1f"), band,
            "" if r["frequency"] is None else "%.1f ± %.1f" % (r["frequency"], r["frequency_std"] or 0.0),
            "" if r["damping"] is None else "%.4f ± %.4f" % (r["damping"], r["damping_std"] or 0.0),
            fmt(r["mac"], "%.3f")))
    stamps = modal.stamps()
    counts = {}
    for s in stamps:
        for r in modal.rows_at(s):
            if r["status"] == "identified" and r["model_mode"] is not None:
                counts[int(r["model_mode"])] = counts.get(int(r["model_mode"]), 0) + 1
    summary = ", ".join("model mode %d in %d" % (m, counts[m]) for m in sorted(counts)) or "no model mode in any"
    which = "the last that matched a model mode" if counts else "the last one"
    return ("Modal identification at %.2f s (%s; %d identifications in all: %s):\n\n%s\n"
            % (stamp - t0, which, len(stamps), summary, "\n".join(out)))
