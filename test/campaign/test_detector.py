#!/usr/bin/python3
"""The campaign's change detector (src/drivetrain_campaign/detector.py) against the CUSUM's closed
form (Page 1954; Montgomery, Introduction to Statistical Quality Control, §9.1): with reference
x_0 = inverse-variance mean, each later bag adds (|d| - f) / sigma to the sum in its direction,
sigma = sqrt(s_i^2 + s_0^2) / x_0, and the alarm is raised while the sum exceeds h."""

import math
import os
import random
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "src"))
from drivetrain_campaign import detector  # noqa: E402


def row(mesh, std, identified=True, status="ok", updates=5):
    return {"status": status, "calibration_updates": updates, "mesh_stiffness_scale": mesh,
            "mesh_stiffness_scale_std": std, "mesh_stiffness_scale_identified": identified}


class ChangeDetector(unittest.TestCase):
    def detect(self, rows, **kw):
        return detector.detect(rows, monitored=("mesh_stiffness_scale",), **kw)

    def test_reference_is_the_inverse_variance_mean_of_the_first_three(self):
        rows = [row(1.0, 0.01), row(1.02, 0.02), row(0.99, 0.01), row(5.0, 0.01)]
        ref = self.detect(rows)["mesh_stiffness_scale"]
        w = [1e4, 2.5e3, 1e4]
        self.assertAlmostEqual(ref["value"], (1e4 * 1.0 + 2.5e3 * 1.02 + 1e4 * 0.99) / sum(w), places=14)
        self.assertAlmostEqual(ref["std"], 1.0 / math.sqrt(sum(w)), places=14)
        self.assertEqual(ref["bags"], 3)

    def test_a_ten_percent_step_adds_the_closed_form_increment_and_raises(self):
        # x_0 = 1, s_0 = 0.004/sqrt(3); a bag at 0.9 with s = 0.004: increment (0.10 - 0.05) / sigma.
        rows = [row(1.0, 0.004) for _ in range(3)] + [row(0.9, 0.004) for _ in range(3)]
        trace = self.detect(rows)["mesh_stiffness_scale"]["trace"]
        sigma = math.sqrt(0.004**2 + 0.004**2 / 3)
        self.assertAlmostEqual(trace[0][2], (0.10 - 0.05) / sigma, places=9)
        self.assertEqual(trace[0][1], 0.0)  # the upward sum stays at zero
        self.assertEqual([r["alarm"] for r in rows], [False] * 3 + [True] * 3)
        self.assertIn("mesh_stiffness_scale -10.0 %", rows[3]["alarm_reason"])

    def test_a_change_below_the_fraction_never_raises_however_sure(self):
        rows = [row(1.0, 1e-4) for _ in range(3)] + [row(1.04, 1e-4) for _ in range(50)]
        self.detect(rows)
        self.assertFalse(any(r["alarm"] for r in rows))

    def test_evidence_accumulates_over_bags_when_each_is_uncertain(self):
        # Step 10 %, sigma = 0.02 * sqrt(1 + 1/3): each bag adds 0.05 / sigma = 2.165; h = 5 is
        # crossed at the third bag after the step (6.50 > 5 > 4.33).
        rows = [row(1.0, 0.02) for _ in range(3)] + [row(0.9, 0.02) for _ in range(4)]
        self.detect(rows)
        self.assertEqual([r["alarm"] for r in rows[3:]], [False, False, True, True])

    def test_unidentified_or_failed_bags_add_nothing(self):
        rows = ([row(1.0, 0.004) for _ in range(3)] + [row(0.8, 0.004, identified=False),
                row(0.8, 0.004, status="refused: not a bag"), row(0.8, 0.004, updates=0)])
        result = self.detect(rows)
        self.assertEqual(result["mesh_stiffness_scale"]["trace"], [])
        self.assertFalse(any(r["alarm"] for r in rows))
        # and cannot enter the reference: the first usable bags do
        rows = [row(0.5, 0.004, identified=False)] + [row(1.0, 0.004) for _ in range(3)]
        self.assertAlmostEqual(self.detect(rows)["mesh_stiffness_scale"]["value"], 1.0, places=14)

    def test_a_campaign_of_two_bags_takes_its_reference_from_the_first_and_still_detects(self):
        rows = [row(1.0, 0.004), row(0.85, 0.004)]
        self.detect(rows, reference_bags=1)
        self.assertEqual([r["alarm"] for r in rows], [False, True])

    def test_no_false_alarm_in_a_constant_campaign_with_honest_standard_deviations(self):
        # 2000 bags drawn around 1 with their own sigma (1 %): the sums drift down by 5 per bag.
        rng = random.Random(4)
        rows = [row(1.0 + rng.gauss(0.0, 0.01), 0.01) for _ in range(2000)]
        self.detect(rows)
        self.assertFalse(any(r["alarm"] for r in rows))

    def test_bad_options_are_refused_by_name(self):
        with self.assertRaisesRegex(ValueError, "fraction"):
            self.detect([row(1.0, 0.01)], fraction=0.0)
        with self.assertRaisesRegex(ValueError, "reference_bags"):
            self.detect([row(1.0, 0.01)], reference_bags=0)


class OutOfFamily(unittest.TestCase):
    """End-of-line: each unit against the batch median (detector.out_of_family)."""

    def test_the_unit_beyond_the_fraction_by_two_of_its_sigmas_is_flagged(self):
        rows = [row(x, 0.005) for x in (1.00, 1.01, 0.99, 1.02, 0.98, 0.92, 1.055)]
        medians = detector.out_of_family(rows, monitored=("mesh_stiffness_scale",))
        self.assertEqual(medians["mesh_stiffness_scale"], 1.0)
        # 0.92: |d| - f = 0.03, / 0.005 = 6 > 2: flagged. 1.055: 0.005 / 0.005 = 1 < 2: within its uncertainty.
        self.assertEqual([r["out_of_family"] for r in rows], [False] * 5 + [True, False])
        self.assertIn("-8.0 % from the batch median", rows[5]["family_reason"])

    def test_a_batch_too_small_for_a_median_flags_nothing(self):
        rows = [row(x, 0.005) for x in (1.0, 0.5, 1.0, 1.0)]
        self.assertEqual(detector.out_of_family(rows, monitored=("mesh_stiffness_scale",)), {})
        self.assertFalse(any(r["out_of_family"] for r in rows))


if __name__ == "__main__":
    unittest.main()
