"""Condition monitoring over a campaign: a two-sided CUSUM per calibrated quantity (docs/campaign.md).

Each bag i gives an estimate x_i with its own standard deviation s_i (the calibration's posterior).
The reference is the inverse-variance mean x_0 of the first `reference_bags` usable bags (default
3, so a campaign of a handful of bags has one), with its standard deviation s_0. Each later bag
gives the relative change d_i = x_i / x_0 - 1 and its standard deviation
sigma_i = sqrt(s_i^2 + s_0^2) / |x_0|, and two CUSUMs (Page 1954, "Continuous inspection schemes",
Biometrika 41; the standardised tabular form of Montgomery, Introduction to Statistical Quality
Control, 6th ed., §9.1) accumulate the evidence of a change larger than the allowed fraction f:

    g+_i = max(0, g+_{i-1} + (d_i - f) / sigma_i),   g-_i = max(0, g-_{i-1} + (-d_i - f) / sigma_i)

and the alarm is raised while either exceeds the decision interval h (default 5). A change below
f drifts the sums down; a change of 2f adds f / sigma_i per bag. A bag whose parameter is not
identified (its posterior is its prior: the data said nothing) or that did not calibrate adds
nothing to that quantity's sums and cannot enter the reference.
"""

import math
import statistics

MONITORED = ("mesh_stiffness_scale", "pinion_bearing_scale", "gear_bearing_scale", "preload_torque")


def finite_number(value):
    """float(value) if it is a finite number, else None (empty CSV cells, None, NaN)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _identified(value):
    return value is True or str(value).lower() == "true"


def usable(row, name):
    """(x, s) of the row's estimate of `name`, or None when it says nothing about the rig."""
    if not str(row.get("status", "")).startswith(("ok", "incomplete")):
        return None
    if not (finite_number(row.get("calibration_updates")) or 0) > 0 or not _identified(row.get(name + "_identified")):
        return None
    x, s = finite_number(row.get(name)), finite_number(row.get(name + "_std"))
    if x is None or s is None or s <= 0.0 or x == 0.0:
        return None
    return x, s


def detect(rows, fraction=0.05, threshold=5.0, reference_bags=3, monitored=MONITORED):
    """Sets row['alarm'] (bool) and row['alarm_reason'] on rows in campaign order; returns, per
    quantity, the reference {"value", "std", "bags"} and the CUSUM trace [(row index, g+, g-)]."""
    if not fraction > 0.0 or not threshold > 0.0 or reference_bags < 1:
        raise ValueError(f"change detector: fraction {fraction}, threshold {threshold}, reference_bags {reference_bags}:"
                         " fraction and threshold must be > 0, reference_bags >= 1")
    for row in rows:
        row["alarm"], row["alarm_reason"] = False, None
    result = {}
    for name in monitored:
        points = [(i, v) for i, v in ((i, usable(r, name)) for i, r in enumerate(rows)) if v is not None]
        reference = points[:reference_bags]
        if not reference:
            result[name] = {"value": None, "std": None, "bags": 0, "trace": []}
            continue
        weights = [1.0 / s**2 for _, (_, s) in reference]
        x0 = sum(w * x for w, (_, (x, _)) in zip(weights, reference)) / sum(weights)
        s0 = 1.0 / math.sqrt(sum(weights))
        up = down = 0.0
        trace = []
        for i, (x, s) in points[len(reference):]:
            d = x / x0 - 1.0
            sigma = math.sqrt(s**2 + s0**2) / abs(x0)
            up = max(0.0, up + (d - fraction) / sigma)
            down = max(0.0, down + (-d - fraction) / sigma)
            trace.append((i, up, down))
            if max(up, down) > threshold:
                row = rows[i]
                row["alarm"] = True
                reason = f"{name} {100.0 * d:+.1f} % (CUSUM {max(up, down):.1f} > {threshold:g})"
                row["alarm_reason"] = reason if not row["alarm_reason"] else row["alarm_reason"] + "; " + reason
        result[name] = {"value": x0, "std": s0, "bags": len(reference), "trace": trace}
    return result


def out_of_family(rows, fraction=0.05, confidence=2.0, minimum=5, monitored=MONITORED):
    """End-of-line view (one bag per unit, no order in time): sets row['out_of_family'] and
    row['family_reason'] where a quantity differs from the batch median by more than `fraction`,
    by at least `confidence` of the bag's own standard deviation beyond that fraction:
    (|x / median - 1| - f) |median| / s > confidence. The median, not the mean, so that the outliers
    do not move the family they are compared with. Needs `minimum` usable bags; returns the
    medians used."""
    for row in rows:
        row["out_of_family"], row["family_reason"] = False, None
    medians = {}
    for name in monitored:
        points = [(i, v) for i, v in ((i, usable(r, name)) for i, r in enumerate(rows)) if v is not None]
        if len(points) < minimum:
            continue
        median = statistics.median(x for _, (x, _) in points)
        medians[name] = median
        for i, (x, s) in points:
            d = x / median - 1.0
            if (abs(d) - fraction) * abs(median) / s > confidence:
                row = rows[i]
                row["out_of_family"] = True
                reason = f"{name} {100.0 * d:+.1f} % from the batch median"
                row["family_reason"] = reason if not row["family_reason"] else row["family_reason"] + "; " + reason
    return medians
