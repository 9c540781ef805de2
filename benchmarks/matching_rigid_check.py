"""What the rigid robust matching spends on its scale check.

``match(moving, fixed, scale=False)`` also fits the best similarity hypothesis, to warn
(``MatchingWarning``) when the sets differ in scale and a rigid fit would pair unrelated
points. This script times that check inside real runs: the calls the check makes (one set
of similarity hypotheses, their scores and one trimmed refinement) are timed in place, on
Kimia-99 outlines of N points, rigid copies with noise of 0.01 of the shape's size, and
compared with the whole rigid match and with a similarity match (``scale=True``) of the
same pair. Medians over the shapes; the load average is printed, as the machine is shared.

    python benchmarks/matching_rigid_check.py            # 33 shapes, N = 50, 100, 200, 400
    python benchmarks/matching_rigid_check.py --quick    # 11 shapes, N = 50, 100
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_line, table
from matching import at_arc, outline


class _CheckTimer:
    """Wraps the robust module's helpers: time spent in calls made for the scale check.

    In a rigid run (``scale=False``) only the check asks for similarity hypotheses
    (``_hypotheses(..., scale=True)``); it then scores them once and refines the best one
    (``_trimmed_refine(..., scale=True)``), which ends the check."""

    def __init__(self, module):
        self.module, self.seconds, self.active = module, 0.0, False
        self.originals = {name: getattr(module, name) for name in ("_hypotheses", "_score", "_trimmed_refine")}

    def _wrap(self, name):
        original = self.originals[name]

        def timed(*args, **kwargs):
            starts = name == "_hypotheses" and kwargs.get("scale") is True
            self.active = self.active or starts
            counted = self.active
            t0 = time.perf_counter()
            out = original(*args, **kwargs)
            if counted:
                self.seconds += time.perf_counter() - t0
            if name == "_trimmed_refine" and kwargs.get("scale") is True:
                self.active = False
            return out

        return timed

    def __enter__(self):
        for name in self.originals:
            setattr(self.module, name, self._wrap(name))
        return self

    def __exit__(self, *exc):
        for name, original in self.originals.items():
            setattr(self.module, name, original)


def rigid_pair(mask, n, rng):
    contour, arc = outline(mask)
    step = arc[-1] / n
    start = rng.uniform(0, arc[-1])
    fixed = at_arc(contour, arc, start + step * np.arange(n))
    size = float(np.linalg.norm(fixed.max(axis=0) - fixed.min(axis=0)))
    truth = at_arc(contour, arc, start + step * (np.arange(n) + rng.uniform(0.25, 0.75)))
    moving = truth + rng.normal(0.0, 0.01 * size, truth.shape)
    angle = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return moving @ rot.T + rng.uniform(-100, 100, 2), fixed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    from centrality_vision.datasets import load_kimia99
    from centrality_vision.matching import _robust, match

    masks = load_kimia99().images[:: 9 if args.quick else 3]
    sizes = (50, 100) if args.quick else (50, 100, 200, 400)
    print(load_line())
    rows = []
    for n in sizes:
        rng = np.random.default_rng(args.seed)
        rigid, check, similarity = [], [], []
        for mask in masks:
            moving, fixed = rigid_pair(mask, n, rng)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                match(moving, fixed, scale=False)  # warm-up (imports, caches)
                with _CheckTimer(_robust) as timer:
                    t0 = time.perf_counter()
                    match(moving, fixed, scale=False)
                    rigid.append(time.perf_counter() - t0)
                check.append(timer.seconds)
                t0 = time.perf_counter()
                match(moving, fixed, scale=True)
                similarity.append(time.perf_counter() - t0)
        rigid, check, similarity = map(np.asarray, (rigid, check, similarity))
        rows.append(
            [
                n,
                len(masks),
                f"{np.median(rigid) * 1e3:.1f}",
                f"{np.median(check) * 1e3:.1f}",
                f"{np.median(check / rigid):.0%}",
                f"{np.median(similarity) * 1e3:.1f}",
                f"{np.median(rigid / similarity):.2f}",
            ]
        )
    print(
        table(
            [
                "N",
                "shapes",
                "rigid match ms",
                "scale check ms",
                "check / rigid",
                "similarity match ms",
                "rigid / similarity",
            ],
            rows,
        )
    )
    print("(medians over the shapes; the check's time is part of the rigid match's)")


if __name__ == "__main__":
    main()
