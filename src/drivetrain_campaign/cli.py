"""drivetrain_campaign's command line (docs/campaign.md)."""

import argparse
import faulthandler
import os
import signal
import shutil
import sys

from . import campaign
from .engine import DaskEngine, SerialEngine, security_from

EXIT_OK, EXIT_REFUSED = 0, 1


def find_replay(given, script_dir):
    """drivetrain_replay: --replay, $DRIVETRAIN_REPLAY, beside this script (an install), the
    package's devel space (scripts/build), each catkin prefix on CMAKE_PREFIX_PATH, then PATH."""
    if given:
        return given
    if os.environ.get("DRIVETRAIN_REPLAY"):
        return os.environ["DRIVETRAIN_REPLAY"]
    root = os.path.dirname(script_dir)
    candidates = [os.path.join(script_dir, "drivetrain_replay"),
                  os.path.join(root, "devel", "lib", "drivetrain_stiffness", "drivetrain_replay"),
                  os.path.join(root, "build", "devel", "lib", "drivetrain_stiffness", "drivetrain_replay")]
    for prefix in filter(None, os.environ.get("CMAKE_PREFIX_PATH", "").split(os.pathsep)):
        candidates.append(os.path.join(prefix, "lib", "drivetrain_stiffness", "drivetrain_replay"))
    for c in candidates:
        if os.access(c, os.X_OK):
            return c
    return shutil.which("drivetrain_replay")


def parser():
    p = argparse.ArgumentParser(
        prog="drivetrain_campaign",
        description="Replays, calibrates and trends every bag of a rig test campaign on dask.distributed "
                    "(docs/campaign.md).")
    p.add_argument("bags", nargs="+", metavar="BAGS", help="bag files, directories (searched recursively for *.bag) or globs")
    p.add_argument("--config", required=True, help="gearbox YAML with a calibration: block (as drivetrain_replay's)")
    p.add_argument("--params", help="the node's parameter YAML (as drivetrain_replay's)")
    p.add_argument("--out", required=True, metavar="DIR", help="campaign.csv, report.md, bags/ and cache/ go here")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="worker processes of the embedded local cluster (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="an existing dask scheduler, e.g. tcp://HOST:8786 or tls://HOST:8786")
    where.add_argument("--serial", action="store_true", help="no cluster: every bag in this process, one after the other")
    p.add_argument("--tls-ca-file", help="--scheduler over TLS: the CA certificate (PEM)")
    p.add_argument("--tls-cert", help="--scheduler over TLS: this client's certificate (PEM)")
    p.add_argument("--tls-key", help="--scheduler over TLS: this client's private key (PEM)")
    p.add_argument("--cache", metavar="DIR", help="result cache (default DIR/cache)")
    p.add_argument("--no-plots", action="store_true", help="bag reports without PNG plots (faster; campaign plots stay)")
    p.add_argument("--bag-outputs", choices=("report", "all"), default="report",
                   help="what each bag's report keeps: report (summary, report.md and its plots, calibrated gearbox, "
                        "the calibration, resonance, spectrum and per-mesh-period CSV files; the default) or all "
                        "(every output topic in outputs.bag and csv/, as drivetrain_replay --report alone: about "
                        "2.3x the bag)")
    p.add_argument("--replay", help="the drivetrain_replay program (found beside this tool or in the devel space)")
    p.add_argument("--alarm-fraction", type=float, default=0.05, help="relative change that raises the alarm (0.05)")
    p.add_argument("--alarm-threshold", type=float, default=5.0, help="CUSUM decision interval h (5)")
    p.add_argument("--reference-bags", type=int, default=3, help="first bags that make the reference (3)")
    return p


def main(argv=None, script_dir=None):
    # `kill -USR1 PID` prints every thread's Python stack to stderr: a campaign that seems stuck
    # says where, without a debugger.
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    args = parser().parse_args(argv)
    script_dir = script_dir or os.path.dirname(os.path.realpath(sys.argv[0]))
    replay = find_replay(args.replay, script_dir)
    try:
        if not replay or not os.access(replay, os.X_OK):
            raise campaign.CampaignError(f"--replay: drivetrain_replay not found or not executable ({replay}); build the "
                                         "package (scripts/build) or pass --replay")
        if args.workers is not None and not 1 <= args.workers <= 1024:
            raise campaign.CampaignError(f"--workers: {args.workers} (1 to 1024)")
        for option, value in (("--alarm-fraction", args.alarm_fraction), ("--alarm-threshold", args.alarm_threshold)):
            if not value > 0.0 or value != value or value == float("inf"):
                raise campaign.CampaignError(f"{option}: {value} (must be finite and > 0)")
        if args.reference_bags < 1:
            raise campaign.CampaignError(f"--reference-bags: {args.reference_bags} (must be >= 1)")
        for option, path in (("--config", args.config), ("--params", args.params)):
            if path and not os.access(path, os.R_OK):
                raise campaign.CampaignError(f"{option}: cannot read '{path}'")
        security = security_from(args.tls_ca_file, args.tls_cert, args.tls_key)
        if security and not args.scheduler:
            raise campaign.CampaignError("--tls-*: only with --scheduler (the embedded cluster stays on the loopback)")
        if args.serial:
            engine = SerialEngine()
        else:
            engine = DaskEngine(workers=args.workers, address=args.scheduler, security=security)
    except (campaign.CampaignError, ValueError, OSError) as e:
        print(f"drivetrain_campaign: {e}", file=sys.stderr)
        return EXIT_REFUSED
    try:
        campaign.run(args.bags, args.config, args.params, args.out, engine, replay, plots=not args.no_plots,
                     cache_dir=args.cache, bag_outputs=args.bag_outputs,
                     detector_options={"fraction": args.alarm_fraction, "threshold": args.alarm_threshold,
                                       "reference_bags": args.reference_bags},
                     log=lambda line: print(line, file=sys.stderr))
    except (campaign.CampaignError, ValueError) as e:
        print(f"drivetrain_campaign: {e}", file=sys.stderr)
        return EXIT_REFUSED
    finally:
        engine.close()
    return EXIT_OK
