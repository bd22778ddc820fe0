"""The campaign's bag list: files, directories (searched recursively for *.bag) and globs."""

import glob
import hashlib
import json
import os


def expand_bags(arguments, exclude=None):
    """Paths in the order given; a directory contributes its *.bag files sorted, a glob its matches
    sorted. A path given twice is listed once. Files below `exclude` (the campaign's own output
    directory, whose reports hold outputs.bag files) are not bags of the campaign. Raises
    ValueError naming an argument that matches nothing (a typo would otherwise shrink the
    campaign silently)."""
    paths, seen = [], set()
    skip = os.path.join(os.path.abspath(exclude), "") if exclude else None
    for arg in arguments:
        if os.path.isdir(arg):
            found = sorted(glob.glob(os.path.join(glob.escape(arg), "**", "*.bag"), recursive=True))
        elif glob.has_magic(arg):
            found = sorted(glob.glob(arg, recursive=True))
        else:
            found = [arg]  # a file, readable or not: an unreadable one gets its refused row
        if skip and (os.path.isdir(arg) or glob.has_magic(arg)):
            found = [p for p in found if not os.path.abspath(p).startswith(skip)]
        if not found:
            raise ValueError(f"BAGS: '{arg}' matches no bag")
        for path in found:
            key = os.path.abspath(path)
            if key not in seen:
                seen.add(key)
                paths.append(path)
    return paths


def hash_bag(path):
    """(path, sha256 or None, error or None): a task, run where the bags are (a worker)."""
    try:
        return path, sha256_of(path), None
    except OSError as e:
        return path, None, f"cannot read '{path}': {e.strerror or e}"


def sha256_of(path, block=1 << 20):
    """Hex SHA-256 of a file's bytes (raises OSError)."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(block), b""):
            digest.update(chunk)
    return digest.hexdigest()


class HashMemo:
    """SHA-256 of bags seen before, keyed by absolute path and trusted while the file's size and
    modification time (ns) are unchanged, as git's index and make trust them. Stat is taken here,
    where the client runs; a path the client cannot stat is hashed by a task every time."""

    def __init__(self, path):
        self.path = path
        try:
            with open(path) as f:
                self.entries = json.load(f)
        except (OSError, ValueError):
            self.entries = {}

    @staticmethod
    def stamp(path):
        """[size, mtime_ns], or None; take it before hashing, so that a bag written meanwhile is
        hashed again next time."""
        try:
            st = os.stat(path)
        except OSError:
            return None
        return [st.st_size, st.st_mtime_ns]

    def get(self, path):
        entry = self.entries.get(path)
        stamp = self.stamp(path)
        return entry["sha256"] if entry and stamp and entry["stat"] == stamp else None

    def put(self, path, sha, stamp):
        if stamp:
            self.entries[path] = {"stat": stamp, "sha256": sha}

    def save(self):
        os.makedirs(os.path.dirname(self.path), exist_ok=True)
        tmp = self.path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(self.entries, f, sort_keys=True)
        os.replace(tmp, self.path)
