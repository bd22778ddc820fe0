"""The accelerometers of a bag (drivetrain_stiffness/VibrationBlock) for the replay report
(plot_replay.py, modal_plots.py):

- read_vibration: the blocks of the first topic of that type, joined into contiguous records;
- spectrogram: short-time power spectral density of one channel of a record;
- averaged_psd: Welch's averaged PSD of each channel over a time span (the stabilisation diagram's
  second axis).
numpy only; SI units (s, Hz, m/s^2, (m/s^2)^2/Hz)."""
import struct

import numpy as np
import rosbag

VIBRATION_TYPE = "drivetrain_stiffness/VibrationBlock"


class Record:
    """Contiguous blocks of one sample rate and one channel list: start [s] (stamp of the first
    sample), sample_rate [Hz], channels (names), data (samples x channels, m/s^2)."""

    def __init__(self, start, sample_rate, channels, data):
        self.start, self.sample_rate, self.channels, self.data = start, sample_rate, channels, data

    @property
    def end(self):
        return self.start + len(self.data) / self.sample_rate


def vibration_topic(bag):
    """The first topic (sorted by name) whose messages are VibrationBlock; None without one."""
    topics = bag.get_type_and_topic_info().topics
    found = sorted(name for name, info in topics.items() if info.msg_type == VIBRATION_TYPE)
    return found[0] if found else None


def read_vibration(bag_path):
    """(topic, records) of the bag's accelerometer blocks; (None, []) without a VibrationBlock
    topic. A block continues the record when it has the record's rate and channels and starts
    within half a block of where the record ends (the replay's rule for unnumbered blocks,
    docs/vibration.md "Block rules"); otherwise it starts a new record. The messages are read raw
    and only the ROS 1 wire format of VibrationBlock is decoded (header, sample_rate, channels[],
    data[]), the float32 samples straight into numpy."""
    u32 = struct.Struct("<I")
    blocks = []
    with rosbag.Bag(bag_path) as bag:
        topic = vibration_topic(bag)
        if topic is None:
            return None, []
        for _, raw, _ in bag.read_messages(topics=[topic], raw=True):
            d = raw[1]
            sec, nsec = struct.unpack_from("<II", d, 4)  # after the header's seq
            o = 12 + 4 + u32.unpack_from(d, 12)[0]  # past frame_id
            rate = struct.unpack_from("<d", d, o)[0]
            o += 8
            names = []
            count = u32.unpack_from(d, o)[0]
            o += 4
            for _ in range(count):
                n = u32.unpack_from(d, o)[0]
                names.append(bytes(d[o + 4:o + 4 + n]).decode("utf-8", "replace"))
                o += 4 + n
            values = u32.unpack_from(d, o)[0]
            if not names or values % len(names) or not rate > 0:
                continue  # the replay refuses such a block too
            data = np.frombuffer(d, dtype="<f4", count=values, offset=o + 4).reshape(-1, len(names))
            blocks.append((sec + 1e-9 * nsec, rate, tuple(names), data))
    records = []
    for start, rate, names, data in blocks:
        last = records[-1] if records else None
        if (last is not None and last[1] == rate and last[2] == names
                and abs(start - last[3]) < 0.5 * len(data) / rate):
            last[4].append(data)
            last[3] += len(data) / rate
        else:
            records.append([start, rate, names, start + len(data) / rate, [data]])
    return topic, [Record(r[0], r[1], list(r[2]), np.concatenate(r[4]).astype(float)) for r in records]


def _segments(x, nperseg, step):
    """The segments of x of nperseg samples every step samples (a view)."""
    count = 1 + (len(x) - nperseg) // step
    return np.lib.stride_tricks.as_strided(x, shape=(count, nperseg), strides=(step * x.strides[0], x.strides[0]))


def _density(segments, rate):
    """One-sided PSD [unit^2/Hz] of each Hann-windowed segment (mean removed): 2 |X|^2 / (fs sum w^2),
    the periodogram's density scaling (Welch 1967)."""
    w = np.hanning(segments.shape[1])
    spec = np.abs(np.fft.rfft((segments - segments.mean(axis=1, keepdims=True)) * w, axis=1)) ** 2
    spec *= 2.0 / (rate * np.sum(w ** 2))
    spec[:, 0] *= 0.5
    if segments.shape[1] % 2 == 0:
        spec[:, -1] *= 0.5
    return spec


def spectrogram(record, channel, nperseg=1024, max_columns=400):
    """Short-time PSD of one channel: Hann segments of nperseg samples overlapping by half, the
    consecutive segments averaged in groups (Welch's average) so that at most max_columns remain.
    Returns (t [s] of each group's centre, frequencies [Hz], psd: frequencies x groups
    [(m/s^2)^2/Hz]); None if the record is shorter than one segment."""
    x = np.ascontiguousarray(record.data[:, channel])
    if len(x) < nperseg:
        return None
    step = nperseg // 2
    psd = _density(_segments(x, nperseg, step), record.sample_rate)
    group = int(np.ceil(len(psd) / max_columns))
    columns = len(psd) // group
    psd = psd[:columns * group].reshape(columns, group, -1).mean(axis=1)
    t = record.start + ((np.arange(columns) * group + 0.5 * (group - 1)) * step + 0.5 * nperseg) / record.sample_rate
    return t, np.fft.rfftfreq(nperseg, 1.0 / record.sample_rate), psd.T


def averaged_psd(records, t_from, t_to, nperseg=4096):
    """Welch's averaged PSD (Hann, half overlap) of each channel over [t_from, t_to] [s] of the
    record that covers most of that span. Returns (frequencies [Hz], psd: channels x frequencies,
    channel names); None if no record holds one segment of it."""
    best, span = None, 0.0
    for r in records:
        s = min(r.end, t_to) - max(r.start, t_from)
        if s > span:
            best, span = r, s
    if best is None:
        return None
    a = int(max(0, np.floor((t_from - best.start) * best.sample_rate)))
    b = int(min(len(best.data), np.ceil((t_to - best.start) * best.sample_rate)))
    if b - a < nperseg:
        return None
    psd = [_density(_segments(np.ascontiguousarray(best.data[a:b, c]), nperseg, nperseg // 2), best.sample_rate).mean(axis=0)
           for c in range(best.data.shape[1])]
    return np.fft.rfftfreq(nperseg, 1.0 / best.sample_rate), np.array(psd), best.channels
