#!/usr/bin/env python3
"""Writes the binary seeds of the pipeline fuzz target (test/data/fuzz/pipeline/*.bin) in the
layout pipeline_decoder.hpp documents. Run from anywhere; the seeds are committed, this script
says what they hold."""
import math
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "fuzz", "pipeline")

# decodeValue's "interesting" table indices
NAN, INF, MINUS_INF, DENORM, MAX_TORQUE_NEXT, PRELOAD_LIMIT_NEXT = 4, 6, 7, 8, 16, 19


def forward(ms):  # stamp: forward by ms milliseconds (16 ns units up to 1 ms, 10 us units beyond)
    if ms <= 1.0:
        return bytes([0]) + struct.pack("<H", int(round(ms * 1e6 / 16)))
    return bytes([2]) + struct.pack("<H", int(round(ms * 100)))


def back(ms):
    return bytes([4]) + struct.pack("<H", int(round(ms * 100)))


BURST, SAME, ZERO = bytes([3, 0]), bytes([5]), bytes([6])


def absolute(sec, nsec):
    return bytes([7]) + struct.pack("<II", sec, nsec)


def typical(x, scale):  # value: x in units of the field's typical scale
    return bytes([2]) + struct.pack("<h", max(-32768, min(32767, int(round(x / scale * 32768)))))


def interesting(i):
    return bytes([0, i])


def raw(x):
    return bytes([1]) + struct.pack("<d", x)


def torque(stamp, value):
    return bytes([0]) + stamp + value


def preload(stamp, settings):
    out = bytes([1]) + stamp + bytes([len(settings)])
    for name_byte, values in settings:
        out += bytes([name_byte]) + b"".join(values)
    return out


def pre(name_byte, axial, radial=1000.0, inner=0.0, outer=0.0):
    return (name_byte, [typical(axial, 3000.0), typical(radial, 3000.0), typical(inner, 2e-5), typical(outer, 2e-5)])


def clock(stamp):
    return bytes([2]) + stamp


def damping(a, b):
    return bytes([3]) + a + b


def fidelity(f):
    return bytes([4, f])


def stiffness_rate(v):
    return bytes([5]) + v


RESET = bytes([6])


def motion(stamp, angle, velocity=None, gear=None, missing=False, numbering=0):
    """joint_states: flags (bit 0 velocity, bit 1 gear angle, 0b111 a missing pinion joint, bits 3-7 numbering)."""
    flags = (7 if missing else (1 if velocity is not None else 0) | (2 if gear is not None else 0)) | numbering
    out = bytes([0xF0]) + stamp + bytes([flags]) + typical(angle, 10.0)
    if velocity is not None and not missing:
        out += typical(velocity, 700.0)
    if gear is not None and not missing:
        out += typical(gear, 10.0)
    return out


# vibration blocks: layout byte bits 0-2 channel names (pipeline_decoder.cpp decodeVibration)
BOTH, GEAR_ONLY, EXTRA_UNKNOWN, NO_CHANNELS, EMPTY_NAME, NONE_KNOWN, REPEATED = range(7)
UNNUMBERED, NEXT, SAME_SEQ, SKIP_SEQ = range(4)
R51200, R51200_WITHIN, R51200_PAST, R25600, R64, R0, R_NEGATIVE = range(7)


def vibration(stamp, frames, rate=R51200, channels=BOTH, numbering=NEXT, size=0, poison=None, amplitude=0.5):
    """One block: `frames` frames of a sine of `amplitude` [m/s^2]; size 2: one sample short of whole
    frames, 3: no samples; poison (index, value bytes): that sample replaced."""
    layout = channels | numbering << 3 | size << 5 | (0x80 if poison else 0)
    out = bytes([0xE0]) + stamp + bytes([layout, rate, frames]) + typical(amplitude, 10.0)
    if poison:
        out += bytes([poison[0]]) + poison[1]
    return out


def block_ms(frames, hz):  # a block's length, the stamp step of continuous blocks
    return frames / hz * 1e3


def encoder_run_up(n, rpm0, rpm1):
    """Torque and joint_states at 1 kHz, the pinion from rpm0 to rpm1, angle wrapped at +-pi."""
    out, angle = b"", 0.0
    for i in range(n):
        w = (rpm0 + (rpm1 - rpm0) * i / max(1, n - 1)) * 2 * math.pi / 60
        angle += w * 1e-3
        wrapped = math.remainder(angle, 2 * math.pi)
        out += torque(forward(0.5), typical(0.1, 0.3)) + motion(forward(0.5), wrapped, w, math.remainder(-0.5 * angle, 2 * math.pi))
    return out


def header(no_dynamics=0, fid=0, ordinary=0, exact_solve=0, rate=0, h1=0, h2=0):
    return bytes([no_dynamics | fid << 1 | ordinary << 3 | exact_solve << 4 | rate << 5, h1, h2])


def ripple(n, step_ms, mean, amp):
    return b"".join(torque(forward(step_ms), typical(mean + amp * math.sin(i), 0.3)) for i in range(n))


seeds = {
    # 1 ms torque ripple around 0.1 N*m, a preload step, the clock following
    "valid_nominal.bin": header() + ripple(10, 1.0, 0.1, 0.02) + preload(forward(1), [pre(0, 2000.0), pre(1, 2000.0)])
    + clock(SAME) + ripple(10, 1.0, 0.1, 0.02),
    # the time rules: zero stamp, out of order, a burst, a gap, a restart far back, the clock going back
    "time_rules.bin": header(h1=0b01 << 6) + ripple(3, 1.0, 0.1, 0.0) + torque(ZERO, typical(0.1, 0.3))
    + torque(back(0.5), typical(0.1, 0.3)) + torque(BURST, typical(0.12, 0.3)) + torque(SAME, typical(0.1, 0.3))
    + torque(forward(600), typical(0.1, 0.3)) + clock(SAME) + clock(back(600)) + torque(back(650), typical(0.1, 0.3))
    + torque(absolute(4294967295, 4294967295), typical(0.1, 0.3)) + torque(absolute(0, 1), typical(0.1, 0.3))
    + ripple(3, 1.0, 0.1, 0.0),
    # values the rules refuse: NaN, Inf, just past max_abs_torque, preloads unknown, negative, past the limit
    "bad_values.bin": header() + ripple(2, 1.0, 0.1, 0.0) + torque(forward(1), interesting(NAN))
    + torque(forward(1), interesting(INF)) + torque(forward(1), interesting(MAX_TORQUE_NEXT))
    + torque(forward(1), raw(-1e300)) + torque(forward(1), interesting(DENORM))
    + preload(forward(1), [(7, [bytes([3]) + b"xyz"] + pre(0, 1.0)[1])])
    + preload(forward(1), [pre(0x80, 1000.0)]) + preload(forward(1), [(0, [interesting(PRELOAD_LIMIT_NEXT)] + pre(0, 0)[1][1:])])
    + preload(forward(1), [pre(6, 1000.0)]) + ripple(2, 1.0, 0.1, 0.0),
    # the run-time setters, good and bad, between inputs
    "setters.bin": header(rate=2) + ripple(3, 1.0, 0.1, 0.0) + damping(typical(0.05, 0.1), typical(0.02, 0.1))
    + damping(interesting(NAN), typical(0.02, 0.1)) + damping(raw(1.5), raw(0.0)) + fidelity(1) + ripple(3, 1.0, 0.1, 0.0)
    + fidelity(2) + ripple(3, 1.0, 0.1, 0.0) + stiffness_rate(raw(-1.0)) + stiffness_rate(typical(100.0, 1000.0))
    + RESET + ripple(3, 1.0, 0.1, 0.0),
    # the ordinary gear (backlash): the torque reverses, the flanks separate
    "ordinary_reversal.bin": header(ordinary=1, h1=0b01 << 2) + ripple(12, 2.0, 0.0, 0.1),
    # no dynamics, every support re-solved, 1 kHz inputs with preload ramps
    # the encoders: a run-up, then a reversal through standstill, without velocity (differentiated)
    "encoder_run_up.bin": header() + encoder_run_up(12, 300.0, 3000.0)
    + b"".join(torque(forward(0.5), typical(0.1, 0.3)) + motion(forward(0.5), 0.3 * math.cos(i / 3)) for i in range(10)),
    # joint_states refused, dropped, out of order, timed out, slipping
    "encoder_faults.bin": header() + encoder_run_up(3, 600.0, 600.0) + motion(forward(1), 0.0, missing=True)
    + motion(forward(1), 0.0) + bytes([0xF0]) + forward(1) + bytes([1]) + interesting(NAN) + typical(60.0, 700.0)
    + motion(back(0.5), 0.1) + motion(ZERO, 0.1) + motion(forward(1), 0.2, numbering=0x10 | 3 << 5)
    + motion(forward(1), 0.3, 60.0, 2.0) + motion(forward(1), 0.35, 60.0, 3.0) + ripple(5, 50.0, 0.1, 0.0)
    + motion(forward(1), 0.0, raw(1e9) and None) + ripple(3, 1.0, 0.1, 0.0),
    # accelerometer blocks at 51.2 kHz, numbered and continuous, then unnumbered 64 Hz blocks that
    # fill a 4 s record: the identification runs (on modes far above that Nyquist frequency)
    "valid_vibration.bin": header() + ripple(2, 1.0, 0.1, 0.0)
    + b"".join(vibration(forward(block_ms(32, 51200)), 32) for _ in range(4))
    + b"".join(vibration(forward(block_ms(32, 64)), 32, rate=R64, numbering=UNNUMBERED) for _ in range(9))
    + ripple(2, 1.0, 0.1, 0.0),
    # blocks the value rules refuse, each after a good one: a NaN sample, a sample past the range,
    # a length not a whole number of frames, no samples, zero and negative rate, no channels, an
    # empty name, no known name, a repeated name
    "invalid_vibration_values.bin": header() + ripple(1, 1.0, 0.1, 0.0) + vibration(forward(0.625), 32)
    + vibration(forward(0.625), 32, poison=(5, interesting(NAN))) + vibration(forward(0.625), 32, poison=(7, raw(2e6)))
    + vibration(forward(0.625), 32, size=2) + vibration(forward(0.625), 32, size=3)
    + vibration(forward(0.625), 32, rate=R0) + vibration(forward(0.625), 32, rate=R_NEGATIVE)
    + vibration(forward(0.625), 32, channels=NO_CHANNELS) + vibration(forward(0.625), 32, channels=EMPTY_NAME)
    + vibration(forward(0.625), 32, channels=NONE_KNOWN) + vibration(forward(0.625), 32, channels=REPEATED)
    + vibration(forward(0.625), 32),
    # the continuity rules: a rate within the tolerance continues, one past it and another rate start
    # new records, a skipped number and a late block are gaps, the same number again and an early
    # block overlap (refused), an unknown extra channel is counted, a changed channel set restarts
    "invalid_vibration_continuity.bin": header() + ripple(1, 1.0, 0.1, 0.0) + vibration(forward(0.625), 32)
    + vibration(forward(0.625), 32, rate=R51200_WITHIN) + vibration(forward(0.625), 32, rate=R51200_PAST)
    + vibration(forward(1.25), 32, rate=R25600) + vibration(forward(1.25), 32, rate=R25600, numbering=SKIP_SEQ)
    + vibration(forward(1.25), 32, rate=R25600, numbering=SAME_SEQ) + vibration(forward(5.0), 32, rate=R25600)
    + vibration(forward(1.25), 32, rate=R25600, numbering=UNNUMBERED)
    + vibration(forward(0.3), 32, rate=R25600, numbering=UNNUMBERED)
    + vibration(forward(1.25), 32, rate=R25600, channels=EXTRA_UNKNOWN)
    + vibration(forward(1.25), 32, rate=R25600, channels=GEAR_ONLY),
    "no_dynamics_preload_ramp.bin": header(no_dynamics=1, exact_solve=1)
    + b"".join(preload(forward(1), [pre(0, 500.0 + 250.0 * i), pre(1, 500.0 + 250.0 * i, inner=2e-6 * i)]) + torque(SAME, typical(0.1, 0.3)) for i in range(8)),
}

os.makedirs(OUT, exist_ok=True)
for name, data in seeds.items():
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)
    print(name, len(data), "bytes")
