"""Results cached by what determines them: the bag's SHA-256, the gearbox and parameter files'
contents, the replay program's bytes and those of the package's shared libraries beside it, the
plot and bag-output options and this package's VERSION. A re-run processes nothing; a campaign
grown by one bag processes one. An entry whose bag report has gone, or holds other topics than
these options write (another run replaced it), is not a hit (the row points at it)."""

import glob
import hashlib
import json
import os

from . import VERSION
from .replay_task import report_topics


def file_digest(path):
    if not path:
        return None
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _names(topics):
    """A --topics list as a set: summary.json and report_topics name the same topics in other orders."""
    return frozenset((topics or "").split(","))


class ResultCache:
    def __init__(self, directory, replay, config, params, plots, bag_outputs="report"):
        self.directory = directory
        os.makedirs(directory, exist_ok=True)
        self.topics = tuple(_names(t) for t in report_topics(plots, bag_outputs))
        # The context every key shares: what else decides a row besides the bag. The replay's own
        # libraries (a catkin build links them shared) change without the program's bytes changing.
        libraries = sorted(glob.glob(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(replay))),
                                                  "libdrivetrain_stiffness*.so*")))
        self.context = json.dumps({"version": VERSION, "replay": file_digest(replay), "config": file_digest(config),
                                   "params": file_digest(params), "plots": bool(plots), "bag_outputs": bag_outputs,
                                   "libraries": [file_digest(p) for p in libraries]}, sort_keys=True)

    def key(self, sha256):
        return hashlib.sha256((self.context + sha256).encode()).hexdigest()

    def _path(self, sha256):
        return os.path.join(self.directory, self.key(sha256) + ".json")

    def get(self, sha256, campaign_dir):
        try:
            with open(self._path(sha256)) as f:
                row = json.load(f)
        except (OSError, ValueError):
            return None
        report = os.path.join(campaign_dir, row.get("report", ""))
        if not os.path.isdir(report):
            return None
        # The same directory name serves every option: a run with other options may have replaced
        # it. A refused bag's report has no summary.json, and nothing in it that depends on them.
        summary_path = os.path.join(report, "summary.json")
        if os.path.exists(summary_path):
            try:
                with open(summary_path) as f:
                    summary = json.load(f)
            except (OSError, ValueError):
                return None
            if (_names(summary.get("topics")), _names(summary.get("csv_topics"))) != self.topics:
                return None
        return row

    def put(self, sha256, row):
        path = self._path(sha256)
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(row, f, sort_keys=True)
        os.replace(tmp, path)
