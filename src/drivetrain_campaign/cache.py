"""Results cached by what determines them: the bag's SHA-256, the gearbox and parameter files'
contents, the replay program's bytes, the plot and bag-output options and this package's VERSION. A re-run
processes nothing; a campaign grown by one bag processes one. An entry whose bag report has gone
is not a hit (the row points at it)."""

import hashlib
import json
import os

from . import VERSION


def file_digest(path):
    if not path:
        return None
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


class ResultCache:
    def __init__(self, directory, replay, config, params, plots, bag_outputs="report"):
        self.directory = directory
        os.makedirs(directory, exist_ok=True)
        # The context every key shares: what else decides a row besides the bag.
        self.context = json.dumps({"version": VERSION, "replay": file_digest(replay), "config": file_digest(config),
                                   "params": file_digest(params), "plots": bool(plots),
                                   "bag_outputs": bag_outputs}, sort_keys=True)

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
        if not os.path.isdir(os.path.join(campaign_dir, row.get("report", ""))):
            return None
        return row

    def put(self, sha256, row):
        path = self._path(sha256)
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(row, f, sort_keys=True)
        os.replace(tmp, path)
