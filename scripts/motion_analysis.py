#!/usr/bin/python3
"""Order tracking of the predicted transmission error against the rig's encoders, for the replay
report (plot_replay.py) and its test (test/replay/check_run_up_spectrum.py).

- read_encoder: the pinion's joint_states (angle unwrapped, speed) from the replay's input bag;
- order_spectrum: the TE resampled on a uniform pinion-angle grid (angle-domain resampling, as
  computed order tracking does it: Fyfe & Munck, Mech. Syst. Signal Process. 11 (1997) 187), then
  an FFT: amplitude against shaft order (cycles per pinion revolution; the mesh is order z_p);
- campbell: short-time spectra of the TE against the mean speed of each window: frequency of the
  strongest line in each window, and the whole map (aliased above the output's Nyquist frequency);
- mesh_order_amplitudes: per time window the amplitude of each mesh order, by least squares on the
  mesh phase of each sample: free of aliasing, whatever the output rate (the Campbell diagram).
numpy only; SI units (rad, rad/s, s, m, Hz)."""
import struct

import numpy as np
import rosbag


def read_encoder(bag_path, joint="pinion", topic="/joint_states"):
    """Stamps [s], unwrapped pinion angle [rad] and speed [rad/s] (the message's velocity, or the
    angle differentiated when the message has none); empty arrays when the bag has no such topic.
    The messages are read raw and only the fields used are decoded (the ROS 1 wire format of
    sensor_msgs/JointState: header, name[], position[], velocity[], effort[]): genpy's full
    deserialisation took 8.0 s for the 240,000 messages of a 48 s load_sweep bag, this 5.4 s, with
    the same arrays bit for bit (rosbag's own reading is the rest)."""
    t, angle, speed = [], [], []
    want = joint.encode()
    u32, f64 = struct.Struct("<I"), struct.Struct("<d")
    with rosbag.Bag(bag_path) as bag:
        for _, raw, _ in bag.read_messages(topics=[topic, topic.lstrip("/")], raw=True):
            if raw[0] != "sensor_msgs/JointState":
                raise ValueError("%s: %s messages on %s, not sensor_msgs/JointState" % (bag_path, raw[0], topic))
            d = raw[1]
            sec, nsec = struct.unpack_from("<II", d, 4)  # after the header's seq
            o = 12 + 4 + u32.unpack_from(d, 12)[0]  # past frame_id
            names = u32.unpack_from(d, o)[0]
            o += 4
            index = -1
            for k in range(names):
                n = u32.unpack_from(d, o)[0]
                if index < 0 and d[o + 4:o + 4 + n] == want:
                    index = k
                o += 4 + n
            positions = u32.unpack_from(d, o)[0]
            first_position = o + 4
            o = first_position + 8 * positions
            velocities = u32.unpack_from(d, o)[0]
            if index < 0 or index >= positions:
                continue
            t.append(sec + 1e-9 * nsec)
            angle.append(f64.unpack_from(d, first_position + 8 * index)[0])
            speed.append(f64.unpack_from(d, o + 4 + 8 * index)[0] if index < velocities else float("nan"))
    t, angle, speed = np.array(t), np.unwrap(np.array(angle)), np.array(speed)
    if len(t) > 1 and np.isnan(speed).any():
        speed = np.gradient(angle, t)
    return t, angle, speed


def order_spectrum(te_t, te, enc_t, enc_angle, samples_per_rev=256, min_revs=4):
    """Amplitude [m] against shaft order of the TE resampled on a uniform pinion-angle grid. Uses
    the longest stretch where the angle increases (or decreases) monotonically; None if it spans
    fewer than min_revs revolutions."""
    theta = np.interp(te_t, enc_t, enc_angle)  # the pinion angle at each TE sample
    d = np.sign(np.diff(theta))
    best, start = (0, 0), 0
    for i in range(1, len(d) + 1):  # longest run of one sign
        if i == len(d) or d[i] != d[start] or d[i] == 0:
            if i - start > best[1] - best[0]:
                best = (start, i + 1)
            start = i
    a, b = best
    th, x = theta[a:b], np.asarray(te[a:b])
    if th[-1] < th[0]:
        th, x = th[::-1], x[::-1]
    revs = (th[-1] - th[0]) / (2 * np.pi)
    if revs < min_revs:
        return None
    n = int(np.floor(revs)) * samples_per_rev
    grid = th[0] + np.arange(n) * (2 * np.pi / samples_per_rev)
    y = np.interp(grid, th, x)
    y = (y - y.mean()) * np.hanning(n)
    amp = 2.0 * np.abs(np.fft.rfft(y)) / np.hanning(n).sum()
    orders = np.fft.rfftfreq(n, d=1.0 / samples_per_rev)  # cycles per revolution
    return orders, amp


def campbell(te_t, te, enc_t, enc_speed, window=0.1, hop=0.05, pad=8):
    """Short-time spectra of the TE (Hann windows of `window` s every `hop` s, zero-padded `pad`
    times): per window the mean pinion speed [rpm], the frequency of the strongest line [Hz]
    (parabolic interpolation of the log amplitude), and the map (speeds, freqs, amplitude)."""
    te_t, te = np.asarray(te_t), np.asarray(te)
    # The mean spacing of the output grid: absolute stamps (~1.8e9 s) hold 0.24 us in a double, so a
    # median of single differences is off by up to that (5005 Hz for a 10 kHz grid's Nyquist).
    dt = (te_t[-1] - te_t[0]) / (len(te_t) - 1)
    n = int(round(window / dt))
    step = max(1, int(round(hop / dt)))
    rows, rpm, peak = [], [], []
    nfft = pad * n
    freqs = np.fft.rfftfreq(nfft, d=dt)
    for s in range(0, len(te) - n + 1, step):
        seg = te[s:s + n]
        spec = np.abs(np.fft.rfft((seg - seg.mean()) * np.hanning(n), nfft))
        spec[freqs < 20.0] = 0.0  # below the slowest mesh line of interest
        k = int(np.argmax(spec))
        if 0 < k < len(spec) - 1 and spec[k - 1] > 0 and spec[k + 1] > 0:
            l0, l1, l2 = np.log(spec[k - 1]), np.log(spec[k]), np.log(spec[k + 1])
            k = k + 0.5 * (l0 - l2) / (l0 - 2 * l1 + l2)
        peak.append(k * (freqs[1] - freqs[0]))
        t_mid = te_t[s:s + n]
        rpm.append(np.mean(np.interp(t_mid, enc_t, enc_speed)) * 60.0 / (2 * np.pi))
        rows.append(spec)
    return np.array(rpm), np.array(peak), (np.array(rpm), freqs, np.array(rows).T if rows else np.zeros((len(freqs), 0)))


def mesh_order_amplitudes(te_t, te, mesh_phase, window=0.1, hop=0.05, max_order=40, orders_in_window=None,
                          max_condition=100.0):
    """Amplitude [m] of mesh orders 1..max_order of the TE in windows of `window` s every `hop` s.
    Each window's samples are fitted by least squares with c_0 + sum_k a_k cos(2 pi k phi) +
    b_k sin(2 pi k phi), phi the mesh phase [-] of each sample (the angle-domain regression of
    docs/calibration.md "Orders, by regression"); the amplitude of order k is hypot(a_k, b_k).
    The regressors are evaluated at the sampling instants, so an order above the output's Nyquist
    frequency is fitted at its own order, not folded onto another: the fit only needs the phases
    of the window's samples to spread over the period (a sampling synchronous with the mesh makes
    it singular). orders_in_window(t_mid) -> the number of orders to fit in the window centred at
    t_mid (at most max_order; None: max_order); a window whose design matrix has a condition
    number above max_condition, or fewer than 4 samples per fitted order, is left NaN.
    Returns (t_mid [s] of each window, amplitudes: windows x max_order, NaN where not fitted)."""
    te_t, te, phase = np.asarray(te_t), np.asarray(te), np.asarray(mesh_phase)
    t_mid, rows = [], []
    if len(te_t) < 2:
        return np.zeros(0), np.zeros((0, max_order))
    # Windows on time, not on sample counts: the output grid may have gaps (a reset).
    starts = np.arange(te_t[0], te_t[-1] - window + 1e-12, hop)
    lo = np.searchsorted(te_t, starts)
    hi = np.searchsorted(te_t, starts + window)
    for s, a, b in zip(starts, lo, hi):
        mid = s + 0.5 * window
        row = np.full(max_order, np.nan)
        k_max = max_order if orders_in_window is None else int(min(max_order, orders_in_window(mid)))
        k_max = min(k_max, (b - a - 1) // 4)
        if k_max >= 1:
            arg = 2 * np.pi * np.outer(phase[a:b], np.arange(1, k_max + 1))
            design = np.hstack([np.ones((b - a, 1)), np.cos(arg), np.sin(arg)])
            coef, _, rank, sv = np.linalg.lstsq(design, te[a:b], rcond=None)
            if rank == design.shape[1] and sv[0] <= max_condition * sv[-1]:
                row[:k_max] = np.hypot(coef[1:k_max + 1], coef[k_max + 1:])
        t_mid.append(mid)
        rows.append(row)
    return np.array(t_mid), np.array(rows).reshape(len(rows), max_order)
