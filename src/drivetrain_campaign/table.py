"""DIR/campaign.csv: one row per distinct bag, sorted by the bag's first stamp (docs/campaign.md).

Values only, no timing: the same campaign gives the same bytes, serial or on a cluster. Numbers are
written in Python's shortest round-trip form, booleans as true/false, missing values empty.
"""

import csv

from .replay_task import CALIBRATED, MODAL_COORDINATES, MODES

COLUMNS = (
    ["bag", "sha256", "start", "duration", "status", "accepted", "rejected", "dropped", "wrong_type",
     "speed_min", "speed_max", "torque_min", "torque_max", "te_rms", "te_peak_to_peak", "mesh_force_mean"]
    + [f"natural_frequency_{i + 1}" for i in range(MODES)]
    + ["modal_identifications"]
    + [f"modal_frequency_{name}{suffix}" for name in MODAL_COORDINATES for suffix in ("", "_std")]
    + ["calibration_updates", "modal_updates", "modal_gated", "calibration_status"]
    + [name + suffix for name in CALIBRATED for suffix in ("", "_std", "_identified")]
    + ["alarm", "alarm_reason", "out_of_family", "family_reason", "duplicates", "report"]
)


def sort_rows(rows):
    """By first stamp; bags without one (refused) last, by path."""
    return sorted(rows, key=lambda r: (r.get("start") is None, r.get("start") or 0.0, r["bag"]))


def _cell(value):
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def write_table(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([_cell(r.get(c)) for c in COLUMNS])


def read_table(path):
    """The rows as strings keyed by column (for tests and tools that trend a finished campaign)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
