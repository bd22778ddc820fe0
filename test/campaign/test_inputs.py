#!/usr/bin/python3
"""The campaign's bag list (src/drivetrain_campaign/inputs.py): files, directories searched
recursively, globs; each path once; the campaign's own output directory left out; an argument
that matches nothing refused by name; SHA-256 against hashlib's known answer."""

import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "src"))
from drivetrain_campaign import inputs  # noqa: E402


class BagList(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name
        for rel in ("a/2.bag", "a/1.bag", "a/deep/3.bag", "a/notes.txt", "out/bags/x/outputs.bag", "b.bag"):
            path = os.path.join(self.root, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w") as f:
                f.write(rel)

    def tearDown(self):
        self.tmp.cleanup()

    def rel(self, paths):
        return [os.path.relpath(p, self.root) for p in paths]

    def test_directories_recursive_sorted_globs_and_files_each_once(self):
        got = inputs.expand_bags([os.path.join(self.root, "a"), os.path.join(self.root, "*.bag"),
                                  os.path.join(self.root, "a", "1.bag")])
        self.assertEqual(self.rel(got), ["a/1.bag", "a/2.bag", "a/deep/3.bag", "b.bag"])

    def test_the_output_directory_is_not_part_of_the_campaign(self):
        everything = inputs.expand_bags([self.root])
        self.assertIn("out/bags/x/outputs.bag", self.rel(everything))
        got = inputs.expand_bags([self.root], exclude=os.path.join(self.root, "out"))
        self.assertNotIn("out/bags/x/outputs.bag", self.rel(got))
        self.assertEqual(len(got), len(everything) - 1)

    def test_an_argument_that_matches_nothing_is_refused_by_name(self):
        with self.assertRaisesRegex(ValueError, "'.*/nothing\\*.bag' matches no bag"):
            inputs.expand_bags([os.path.join(self.root, "nothing*.bag")])

    def test_sha256_known_answer_and_unreadable_path(self):
        path = os.path.join(self.root, "abc")
        with open(path, "wb") as f:
            f.write(b"abc")
        # FIPS 180-2, appendix B.1: SHA-256("abc")
        self.assertEqual(inputs.sha256_of(path), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad")
        _, sha, error = inputs.hash_bag(os.path.join(self.root, "missing.bag"))
        self.assertIsNone(sha)
        self.assertIn("cannot read", error)

    def test_the_hash_memo_trusts_size_and_mtime_only(self):
        bag = os.path.join(self.root, "b.bag")
        memo_path = os.path.join(self.root, "memo", "hashes.json")
        memo = inputs.HashMemo(memo_path)
        self.assertIsNone(memo.get(bag))
        memo.put(bag, "f" * 64, memo.stamp(bag))
        memo.save()
        self.assertEqual(inputs.HashMemo(memo_path).get(bag), "f" * 64)  # read back from disk
        st = os.stat(bag)
        os.utime(bag, ns=(st.st_atime_ns, st.st_mtime_ns + 1))  # touched: hashed again
        self.assertIsNone(inputs.HashMemo(memo_path).get(bag))
        self.assertIsNone(memo.get(os.path.join(self.root, "gone.bag")))


if __name__ == "__main__":
    unittest.main()
