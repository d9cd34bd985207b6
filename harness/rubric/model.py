"""The check model and the rating scale: what a rubric check is, what a measure returns, and how
negatives become ratings (thesis chapter 5, Table 5.2; restated in ``shared/spec/rubric.md``).

This module holds no threshold: every check, with its thresholds and their reasons, is declared
in :mod:`cassi.harness.rubric.registry`.
"""
from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.versions.registry import BUILT_IN_VERSIONS

__all__ = ["RATINGS", "GOOD_RATINGS", "TABLES", "TABLE_TOPICS", "VERSION_ORDER", "rate",
           "table_title", "Measurement", "Check"]

#: Thesis Table 5.2: negatives -> rating (6 or more: UNACCEPTABLE).
RATINGS = ("EXCELLENT", "VERY GOOD", "GOOD", "FAIR", "POOR", "VERY POOR", "UNACCEPTABLE")
#: The ratings the thesis's summaries count as good (Table 5.6: "VERY GOOD or EXCELLENT").
GOOD_RATINGS = ("EXCELLENT", "VERY GOOD")

#: Rubric tables: letter -> (thesis table, title). F is cassi-farm's addition, not the thesis's.
TABLES = {
    "A": ("5.3", "Teeth, lips and tongue per subject"),
    "B": ("5.4", "Overall face shape at initialization"),
    "C": ("5.5", "Lip placement and movement across versions"),
    "D": ("5.8", "Maximum lip protrusion, task 118"),
    "E": ("5.9", "Jaw wagging, task 106"),
    "F": ("", "Fidelity to the recording (cassi-farm's addition, not in the thesis)"),
    "G": ("", "Shape between the pellets (cassi-farm's addition, not in the thesis)"),
}
#: What each table judges, for the "versions compared" sentences.
TABLE_TOPICS = {"A": "teeth, lips and tongue", "B": "face shape", "C": "lip placement",
                "D": "maximum lip protrusion", "E": "jaw wagging", "F": "fidelity to the recording",
                "G": "the lips and tongue between the pellets"}

#: Versions in the order the thesis compares them (Table C: "compared with the previous
#: version"): the version registry's built-ins, in its order.
VERSION_ORDER = tuple(BUILT_IN_VERSIONS)
#: The version that keeps Parke's face (the first built-in): Table B's figures are ratios over
#: its neutral face, so a reviewer sees a Table B verdict beside it.
PARKE_VERSION = VERSION_ORDER[0]


def shown_beside(check_table: str, version: str, versions) -> str | None:
    """The version a verdict's viewer link shows beside ``version``: Parke's face for Table B
    (its figures are ratios over Parke's neutral face), when the run has it; else none."""
    if check_table == "B" and version != PARKE_VERSION and PARKE_VERSION in set(versions):
        return PARKE_VERSION
    return None


def rate(negatives: int) -> str:
    """The rating for a number of negatives (thesis Table 5.2).

    >>> rate(0), rate(3), rate(6), rate(11)
    ('EXCELLENT', 'FAIR', 'UNACCEPTABLE', 'UNACCEPTABLE')
    """
    n = int(negatives)
    if n < 0:
        raise CassiInputError(f"negatives must be >= 0, got {n}")
    return RATINGS[min(n, len(RATINGS) - 1)]


def table_title(table: str) -> str:
    """``Teeth, lips and tongue, per subject (thesis Table 5.3)``; Table F says it is ours."""
    thesis, title = TABLES.get(str(table), ("", f"Table {table}"))
    return f"{title} (thesis Table {thesis})" if thesis else title


@dataclass(frozen=True)
class Measurement:
    """What a measure returns: the whole-task value, the worst frame and a detail text.

    ``series`` (optional, (F,)) is the per-frame value; ``negatives`` overrides the threshold
    grading for checks whose thesis rule is not a plain threshold (tongue: upper / lower / both).
    """

    value: float
    frame: int = -1
    detail: str = ""
    negatives: int | None = None
    frame_value: float | None = None


@dataclass(frozen=True, kw_only=True)
class Check:
    """One rubric criterion.

    Attributes
    ----------
    name : str
        Unique registry key (the ``check`` column).
    table : str
        ``A`` .. ``G`` (:data:`TABLES`); ``thesis_table`` the thesis's table number ("" for F, G).
    component : str
        teeth, lips, tongue, palate, jaw, face ...
    view : str
        Where the thesis judged it: front, side, half, top (the results' ``view`` column is
        ``geometry`` for geometric checks, the render view for image checks).
    unit : str
    frames : str
        Which frames it looks at.
    description : str
        What it measures.
    thresholds : tuple of float
        Values beyond which the fault counts, mildest first.
    negatives : tuple of int
        Negatives earned beyond each threshold (same length, non-decreasing).
    direction : {"higher", "lower"}
        ``higher``: larger values are worse (fires when value > threshold); ``lower``: smaller
        values are worse (fires when value < threshold).
    reason : str
        Why these threshold values.
    text : str
        The negative as the thesis writes it.
    kind : {"geometry", "image", "fidelity"}
        What the measure reads: the animation (:class:`~cassi.harness.rubric.measures.GeometryContext`),
        the rendered masks (:class:`~cassi.harness.rubric.image.ImageContext`) or the animation
        with the recording it animated (:class:`~cassi.harness.rubric.fidelity.FidelityContext`).
    measure : str
        ``"module:function"`` inside this package, ``function(ctx) -> Measurement``; resolved
        when first called, so the registry imports no measure code.
    tasks : tuple of int or None
        Only these tasks (118 for Table D, 106 for Table E); None = every task but ``skip_tasks``.
    skip_tasks : tuple of int
        Tasks a check with ``tasks=None`` never judges: the registry gives Tables A-C's checks
        the oral-motor tasks 106 and 118, which Tables D and E judge (``SPEECH_TABLES``).
    counted : bool
        False for what the thesis measured but did not count (tongue through the palate) and
        for image cross-checks of a geometric check; such rows always carry 0 negatives.
    gate_tolerance : int
        Extra negatives (summed over subjects) the metric gate of ``cassi gate`` allows.
    charged_with : str or None
        One fault, one charge: this check earns nothing for a subject and version when the named
        check already charges the same fault (the aggregation applies it).
    ranges : tuple of (low, high) or None
        The plausible range of each threshold the rubric chose itself (same length as
        ``thresholds``; None for a threshold the thesis or a cited source fixes), declared before
        any sensitivity run: ``cassi sensitivity`` re-grades the stored values at each end.
        Empty: no threshold of the check is ranged.
    range_reason : str
        Why those ends (what a viewer sees, the thesis, literature).
    at_rest : str
        Non-empty for a measure of the face at rest (its first frame), not of its movement: why.
        A face that stands still is judged on it as any face with the same rest, so such a check
        is exempt from "a face that stands still scores worst" on the movement checks.
    """

    name: str
    table: str
    component: str
    view: str
    unit: str
    frames: str
    description: str
    thresholds: tuple[float, ...]
    negatives: tuple[int, ...]
    direction: str
    reason: str
    text: str
    kind: str
    measure: str
    tasks: tuple[int, ...] | None = None
    skip_tasks: tuple[int, ...] = ()
    counted: bool = True
    gate_tolerance: int = 0
    charged_with: str | None = None
    ranges: tuple[tuple[float, float] | None, ...] = ()
    range_reason: str = ""
    at_rest: str = ""

    def __post_init__(self):
        if self.table not in TABLES:
            raise ValueError(f"{self.name}: unknown table {self.table!r}")
        if len(self.thresholds) != len(self.negatives) or not self.thresholds:
            raise ValueError(f"{self.name}: one negatives count per threshold")
        if list(self.negatives) != sorted(self.negatives) or min(self.negatives) < 1:
            raise ValueError(f"{self.name}: negatives must be >= 1 and non-decreasing")
        step = np.diff(self.thresholds)
        if self.direction == "higher" and np.any(step <= 0) or \
           self.direction == "lower" and np.any(step >= 0):
            raise ValueError(f"{self.name}: thresholds must run from mild to severe")
        if self.kind not in ("geometry", "image", "fidelity"):
            raise ValueError(f"{self.name}: kind must be geometry, image or fidelity")
        if self.direction not in ("higher", "lower"):
            raise ValueError(f"{self.name}: direction must be higher or lower")
        if ":" not in self.measure:
            raise ValueError(f"{self.name}: measure must be 'module:function'")

    def verify_ranges(self) -> None:
        """Each declared range holds its threshold, and either end keeps the thresholds' order
        (the registry asks at start-up; a check built with other thresholds is not asked)."""
        if not self.ranges:
            return
        if len(self.ranges) != len(self.thresholds) or not self.range_reason:
            raise ValueError(f"{self.name}: one range (or None) per threshold, and a range_reason")
        for i, (t, r) in enumerate(zip(self.thresholds, self.ranges)):
            if r is not None and not r[0] < t < r[1]:
                raise ValueError(f"{self.name}: threshold {t} must lie inside its range {r}")
            for end in () if r is None else r:  # each end keeps the thresholds' order
                self.with_threshold(i, end)

    def with_threshold(self, index: int, value: float) -> "Check":
        """This check with threshold ``index`` set to ``value`` (one end of its range); the
        thresholds must still run from mild to severe."""
        t = list(self.thresholds)
        t[index] = float(value)
        return dataclasses.replace(self, thresholds=tuple(t), ranges=())

    @property
    def func(self):
        """The measure, ``func(ctx) -> Measurement`` (imported on first use)."""
        module, name = self.measure.split(":", 1)
        return getattr(importlib.import_module(f"{__package__}.{module}"), name)

    @property
    def side(self) -> str:
        """Which side of the threshold is a fault, in words (evidence pages)."""
        return "above is a fault" if self.direction == "higher" else "below is a fault"

    @property
    def thesis_table(self) -> str:
        return TABLES[self.table][0]

    @property
    def threshold(self) -> float:
        """The first (mildest) threshold: where the check starts to fire."""
        return float(self.thresholds[0])

    def applies_to(self, task: int | None) -> bool:
        if self.tasks is not None:
            return task is not None and int(task) in self.tasks
        return task is None or int(task) not in self.skip_tasks

    def grade(self, value: float) -> int:
        """Negatives for a value by the thresholds (0 when not counted or not measurable)."""
        if value is None or not np.isfinite(value):
            return 0
        n = 0
        for t, k in zip(self.thresholds, self.negatives):
            if (value > t) if self.direction == "higher" else (value < t):
                n = k
        return n

    def fires(self, value: float) -> bool:
        return value is not None and np.isfinite(value) and (
            value > self.threshold if self.direction == "higher" else value < self.threshold)

