"""The campaign: bags in, DIR/campaign.csv, DIR/report.md and DIR/bags/ out (docs/campaign.md)."""

import glob
import json
import os
import shutil
import sys
import time

import yaml

from . import detector, inputs, report, table
from .cache import ResultCache
from .replay_task import BAG_OUTPUTS, run_replay


class CampaignError(Exception):
    """A campaign that cannot start (options, files, a cluster that cannot read the bags)."""


def check_gearbox(config):
    """Refuses a gearbox file that cannot be read or has no calibration: block (the replay would
    refuse every bag's --calibrate), before any bag is touched."""
    try:
        with open(config) as f:
            doc = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise CampaignError(f"--config: cannot read '{config}': {e}") from e
    if not isinstance(doc, dict) or not isinstance(doc.get("calibration"), dict):
        raise CampaignError(f"--config '{config}': no calibration: block; a campaign replays every bag with "
                            "calibration (docs/calibration.md)")


def _stem(path):
    name = os.path.basename(path)
    return name[:-4] if name.endswith(".bag") else name


def _progress(total):
    from tqdm import tqdm

    return tqdm(total=total, unit="bag", file=sys.stderr, dynamic_ncols=True, smoothing=0.1,
                bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} bags [{elapsed}<{remaining}{postfix}]")


def run(bags, config, params, out_dir, engine, replay, plots=True, cache_dir=None, detector_options=None, log=print,
        bag_outputs="report"):
    """Runs the campaign on `engine` (engine.SerialEngine or engine.DaskEngine); returns a dict with
    the rows (campaign order) and what was processed. bag_outputs: "report" (each bag's report keeps
    the topics it needs, replay_task.REPORT_TOPICS) or "all" (every output topic, as
    `drivetrain_replay --report` alone)."""
    if bag_outputs not in BAG_OUTPUTS:
        raise CampaignError(f"--bag-outputs: '{bag_outputs}' ({' or '.join(BAG_OUTPUTS)})")
    wall_start = time.monotonic()
    config, params, replay = (os.path.abspath(p) if p else None for p in (config, params, replay))
    check_gearbox(config)
    out_dir = os.path.abspath(out_dir)
    paths = inputs.expand_bags(bags, exclude=out_dir)
    bag_root = os.path.join(out_dir, "bags")
    os.makedirs(bag_root, exist_ok=True)
    _remove_scratch(bag_root)  # a killed earlier run's

    # Every worker must read what the client can (shared storage): else a set-up error, not rows.
    readable_here = [os.path.abspath(p) for p in paths if os.access(p, os.R_OK)]
    problems = {w: p for w, p in engine.preflight(readable_here + [config] + ([params] if params else []), [replay],
                                                  [bag_root]).items() if p}
    if problems:
        lines = [f"  worker {w}: {', '.join(p[:5])}{' ...' if len(p) > 5 else ''}" for w, p in sorted(problems.items())]
        raise CampaignError("the workers cannot use the campaign's files (bags, gearbox, drivetrain_replay and "
                            f"{bag_root} must be at the same paths on every worker):\n" + "\n".join(lines))

    cache = ResultCache(cache_dir or os.path.join(out_dir, "cache"), replay, config, params, plots, bag_outputs)
    rows, jobs, first_path, duplicates = [], [], {}, {}
    # A bag whose path, size and modification time are those of an earlier run keeps its SHA-256:
    # a re-run of a large campaign reads no bag at all (a changed or touched bag is hashed again).
    memo = inputs.HashMemo(os.path.join(cache_dir or os.path.join(out_dir, "cache"), "hashes.json"))
    hashed = {}
    for p in paths:
        sha = memo.get(os.path.abspath(p))
        if sha:
            hashed[os.path.abspath(p)] = (sha, None)
    to_hash = [os.path.abspath(p) for p in paths if os.path.abspath(p) not in hashed]
    stamps = {p: memo.stamp(p) for p in to_hash}
    for path, result, task_error in engine.map_unordered(inputs.hash_bag, to_hash):
        hashed[path] = (result[1], result[2]) if result else (None, task_error)
        if hashed[path][0]:
            memo.put(path, hashed[path][0], stamps[path])
    memo.save()
    for path in paths:
        sha, error = hashed[os.path.abspath(path)]
        if sha is None:
            rows.append({"bag": path, "status": f"refused: {error or 'cannot read'}"})
            continue
        if sha in first_path:  # the same bytes under another name: reported once
            duplicates.setdefault(sha, []).append(path)
            continue
        first_path[sha] = path
        cached = cache.get(sha, out_dir)
        if cached is not None:
            cached["bag"] = path
            rows.append(cached)
            continue
        jobs.append({"bag": os.path.abspath(path), "given": path, "sha256": sha, "replay": replay, "config": config,
                     "params": params, "plots": plots, "bag_outputs": bag_outputs, "campaign_dir": out_dir,
                     "out_dir": os.path.join(bag_root, f"{_stem(path)}-{sha[:8]}")})

    failed = 0
    bar = _progress(len(jobs))
    try:
        for job, row, error in engine.map_unordered(run_replay, jobs):
            if row is None:
                row = {"bag": job["given"], "sha256": job["sha256"], "status": f"refused: campaign task failed: {error}"}
            else:
                row["bag"] = job["given"]
                cache.put(job["sha256"], row)
            if str(row["status"]).startswith("refused"):
                failed += 1
                bar.write(f"drivetrain_campaign: {row['bag']}: {row['status']}", file=sys.stderr)
            rows.append(row)
            bar.set_postfix_str(f"{failed} refused" if failed else "", refresh=False)
            bar.update(1)
    finally:
        bar.close()
    _remove_scratch(bag_root)  # a lost worker's: its task ran again elsewhere

    for sha, others in duplicates.items():
        for row in rows:
            if row.get("sha256") == sha:
                row["duplicates"] = ";".join(others)
    rows = table.sort_rows(rows)
    references = detector.detect(rows, **(detector_options or {}))
    detector.out_of_family(rows, fraction=(detector_options or {}).get("fraction", 0.05))
    table.write_table(os.path.join(out_dir, "campaign.csv"), rows)
    report.write_report(out_dir, rows, references, detector_options or {})
    result = {"bags": len(paths), "distinct": len(first_path) + sum(1 for r in rows if not r.get("sha256")),
              "hashed": len(to_hash), "processed": len(jobs), "cached": len(first_path) - len(jobs),
              "duplicates": sum(len(v) for v in duplicates.values()),
              "refused": sum(1 for r in rows if str(r.get("status")).startswith("refused")),
              "alarms": sum(1 for r in rows if r.get("alarm")), "engine": engine.name, "workers": engine.workers,
              "wall_s": time.monotonic() - wall_start}
    with open(os.path.join(out_dir, "run.json"), "w") as f:
        json.dump(result, f, indent=2)  # timing lives here, never in campaign.csv
    result["rows"] = rows
    log(f"drivetrain_campaign: {result['bags']} bags ({result['processed']} replayed, {result['cached']} from the cache, "
        f"{result['duplicates']} duplicates, {result['refused']} refused), {result['alarms']} with alarm; "
        f"{out_dir}/campaign.csv, {out_dir}/report.md ({result['wall_s']:.1f} s on {engine.name})")
    return result


def _remove_scratch(bag_root):
    for leftover in glob.glob(os.path.join(bag_root, "*.part-*")):
        shutil.rmtree(leftover, ignore_errors=True)
