"""The elliptical front view of CASSI 2.0's lips (thesis section 4.2.1), as pure functions.

Front view: y is the horizontal axis (0 on the mid-sagittal centre line, positive to the face's
left; the face model holds the left half only) and z the vertical axis, both in Parke units.
In the thesis's notation ``a`` is always the half-WIDTH and ``b`` the half-HEIGHT of an ellipse,
and ``c`` its focal distance: horizontal (b < a) or vertical (b >= a, "ellipse switch").

Everything except Algorithm OUTER_ABC_CALC is elementwise over frames (arrays of shape (F,));
OUTER_ABC_CALC is a recurrence over frames and runs as a tight loop over plain floats
(:func:`outer_abc_sequence`), each step through the one implementation :func:`outer_abc_step`.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import NOMINAL_PERIOD_US

from cassi.versions import lips_constants as K

__all__ = [
    "BRANCH_LABELS",
    "OuterAbcParams",
    "TUNINGS",
    "OuterAbcState",
    "OuterAbcTrack",
    "c_prime",
    "ellipse_z",
    "focal_c",
    "is_vertical",
    "limit_abc",
    "major_a",
    "mid_inner_abc",
    "outer_abc_sequence",
    "outer_abc_step",
    "tuning",
]

#: Which branch of OUTER_ABC_CALC (Figure 4.18) produced a frame's a and c, by code.
#: 0 "3": NewSubject (first frame of a task); 1 "3a": height increasing, c' near c_rest (width
#: shrinks); 2 "3b": height decreasing, c' near c_rest (width grows); 3 "3c-ii": c smoothed,
#: horizontal ellipse or small c', a from Eq. 4.8; 4 "3c-iii": c smoothed, ellipse may be
#: vertical, a follows the height and c from Eq. 4.14.
BRANCH_LABELS: tuple[str, ...] = ("3", "3a", "3b", "3c-ii", "3c-iii")
BRANCH_NEW, BRANCH_DROP, BRANCH_RISE, BRANCH_HORIZONTAL, BRANCH_VERTICAL = range(5)


def c_prime(
    x_curr,
    x_rest: float,
    x_max: float,
    x_min: float,
    *,
    c_rest: float = K.C_REST,
    c_min: float = K.C_MIN,
    c_max: float = K.C_MAX,
) -> np.ndarray:
    """Equation 4.13: the roundness estimate c' from the upper lip's forward position.

    Parameters
    ----------
    x_curr : float or array (F,)
        x of vertex 67 (the upper lip pellet), Parke units.
    x_rest, x_max, x_min : float
        The subject's resting, most forward and most retracted upper lip x (maxprotru.txt's
        REST UL, MAX UL, MIN UL) mapped into Parke space; ``x_min < x_rest < x_max``.
    c_rest, c_min, c_max : float
        Key c values (65, 0, 85 in the thesis).

    Returns
    -------
    ndarray (F,)
        c'. Linear from (x_rest, c_rest) to (x_max, c_min) in front of rest and to
        (x_min, c_max) behind it; not clipped (a lip beyond the subject's sampled extremes gives
        c' outside [c_min, c_max], as the equation does).

    Raises
    ------
    CassiInputError
        When the key x values are not ordered ``x_min < x_rest < x_max`` (the equation would
        divide by zero or invert rounding and stretching).
    """
    if not (x_min < x_rest < x_max):
        raise CassiInputError(
            f"maxprotru key x values must satisfy MIN UL < REST UL < MAX UL, got "
            f"x_min={x_min!r}, x_rest={x_rest!r}, x_max={x_max!r}"
        )
    x = np.asarray(x_curr, dtype=np.float64)
    dx = x - x_rest
    forward = dx * ((c_min - c_rest) / (x_max - x_rest)) + c_rest
    backward = dx * ((c_max - c_rest) / (x_min - x_rest)) + c_rest
    return np.where(x > x_rest, forward, backward)


def major_a(b, c) -> np.ndarray:
    """Equation 4.8: ``a = sqrt(b^2 + c^2)`` (width from height and focal distance)."""
    b = np.asarray(b, dtype=np.float64)
    c = np.asarray(c, dtype=np.float64)
    return np.sqrt(b * b + c * c)


def focal_c(a, b) -> np.ndarray:
    """Equation 4.14: ``c = sqrt(a^2 - b^2)`` if b < a (horizontal), else ``sqrt(b^2 - a^2)``.

    ``a`` is the half-width and ``b`` the half-height (Parke units); the result is continuous
    through the switch (0 at b = a).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return np.sqrt(np.abs(a * a - b * b))


def is_vertical(a, b) -> np.ndarray:
    """True where the ellipse is vertical (height >= width, Eq. 4.14's 'otherwise')."""
    return np.asarray(b) >= np.asarray(a)


@dataclass(frozen=True)
class OuterAbcParams:
    """The tuning of OUTER_ABC_CALC (defaults from :mod:`lips_constants`, with reasons).

    The band "c' near c_rest" of steps 3(a)/3(b) is ``near_c_rest`` c' units either side of
    c_rest, unless ``near_rest_mm`` is given: then it is that many mm of the upper lip's x either
    side of the subject's rest, in c' units by Eq. 4.13's slope on each side
    (:meth:`for_subject` resolves it into ``near_forward`` / ``near_back``).
    """

    # read when built, not when imported: cassi.versions.ranges sets them for a while
    rho: float = field(default_factory=lambda: K.RHO)
    near_c_rest: float = field(default_factory=lambda: K.NEAR_C_REST)
    small_c_prime: float = field(default_factory=lambda: K.SMALL_C_PRIME)
    c_rest: float = K.C_REST
    width_rate_divisor: float = K.WIDTH_RATE_DIVISOR
    near_rest_mm: float | None = None
    #: The band below c_rest (lips forward, rounding) and above it (lips back), c' units; None:
    #: ``near_c_rest``.
    near_forward: float | None = None
    near_back: float | None = None

    def __post_init__(self) -> None:
        if not 0.0 < self.rho <= 1.0:
            raise CassiInputError(f"rho must lie in (0, 1], got {self.rho!r}")
        if self.near_c_rest < 0 or self.width_rate_divisor <= 0:
            raise CassiInputError("near_c_rest must be >= 0 and width_rate_divisor > 0")
        for name in ("near_rest_mm", "near_forward", "near_back"):
            v = getattr(self, name)
            if v is not None and not v >= 0:
                raise CassiInputError(f"{name} must be >= 0, got {v!r}")

    @property
    def band(self) -> tuple[float, float]:
        """(below, above) c_rest: c' is near c_rest when c_rest - below <= c' <= c_rest + above."""
        below = self.near_c_rest if self.near_forward is None else self.near_forward
        above = self.near_c_rest if self.near_back is None else self.near_back
        return below, above

    def for_subject(self, x_rest: float, x_max: float, x_min: float,
                    units_per_mm: float | None) -> "OuterAbcParams":
        """These parameters with the band resolved for a subject (``near_rest_mm`` of the upper
        lip's x, Parke units = mm * ``units_per_mm``, through Eq. 4.13's slope on each side);
        unchanged when the band is given in c' units."""
        if self.near_rest_mm is None:
            return self
        if units_per_mm is None or not units_per_mm > 0:
            raise CassiInputError("a band in mm of the upper lip (near_rest_mm) needs the "
                                  f"subject's Parke units per mm, got {units_per_mm!r}")
        dx = self.near_rest_mm * units_per_mm
        return dataclasses.replace(
            self, near_rest_mm=None,
            near_forward=dx * (self.c_rest - K.C_MIN) / (x_max - x_rest),
            near_back=dx * (K.C_MAX - self.c_rest) / (x_rest - x_min))

    def for_period(self, period_us: float) -> "OuterAbcParams":
        """These parameters for a recording sampled every ``period_us``: rho is a rate per XRMB
        row, so at another rate it is the same smoothing per second.

        Step 3(c)i is defined per frame, but the thesis gives rho no value; the value here is
        chosen for its time constant (about 65 ms at XRMB's rows, :data:`~.lips_constants.RHO`),
        so a 500 Hz recording keeps that time constant: the memory (1 - rho) per row becomes
        (1 - rho) ** (period / 6866 us). Unchanged on an XRMB recording (byte for byte) and for
        rho 1 (no smoothing: 2.0)."""
        if period_us == NOMINAL_PERIOD_US or self.rho == 1.0:
            return self
        rho = 1.0 - (1.0 - self.rho) ** (float(period_us) / NOMINAL_PERIOD_US)
        return dataclasses.replace(self, rho=min(1.0, rho))


#: Each version's OUTER_ABC_CALC tuning, by name (the thesis gives neither: 2.0 and 2.1 were
#: tuned on tasks 106 and 118, section 5.4). "2.0": the thesis's equations with the least added
#: smoothing that stays stable (rho 1); "2.1": the tuning that removes the switch jitter (rho
#: 0.1); both with the band of the upper lip within the pellets' precision of rest. "shared":
#: the one tuning both versions had before (rho 0.1, a band of 5 c' units for every subject).
#: Built when asked for, not when imported: cassi.versions.ranges sets the constants for a while.
TUNINGS: dict[str, Callable[[], OuterAbcParams]] = {
    "2.0": lambda: OuterAbcParams(rho=K.RHO_20, near_rest_mm=K.NEAR_REST_MM),
    "2.1": lambda: OuterAbcParams(rho=K.RHO, near_rest_mm=K.NEAR_REST_MM),
    "shared": OuterAbcParams,
}


def tuning(name: str) -> OuterAbcParams:
    """The named OUTER_ABC_CALC tuning (:data:`TUNINGS`), built from today's constants; a clear
    error for an unknown name."""
    try:
        return TUNINGS[name]()
    except KeyError:
        raise CassiInputError(f"unknown lip tuning {name!r}; known: {', '.join(TUNINGS)}") from None


@dataclass
class OuterAbcState:
    """The state OUTER_ABC_CALC carries from frame to frame (Figure 4.18's inputs).

    ``new_subject`` is the NewSubject flag: true for the first frame of a task file.
    """

    prev_a: float = 0.0
    prev_b: float = 0.0
    prev_c: float = 0.0
    new_subject: bool = True


def outer_abc_step(
    b: float,
    cp: float,
    prev_a: float,
    prev_b: float,
    prev_c: float,
    new_subject: bool,
    params: OuterAbcParams,
) -> tuple[float, float, int]:
    """One frame of Algorithm OUTER_ABC_CALC (thesis Figure 4.18), on plain floats.

    Parameters
    ----------
    b : float
        Height of the outer outline (step 1): half the vertical distance 67 - 49, >= 0.
    cp : float
        c' of this frame (step 2, Eq. 4.13).
    prev_a, prev_b, prev_c : float
        The previous frame's outputs (ignored when ``new_subject``).
    new_subject : bool
        First frame of a task file.
    params : OuterAbcParams

    Returns
    -------
    (a, c, branch) : (float, float, int)
        Width, focal distance and the branch code (index into :data:`BRANCH_LABELS`). Step 4
        (saving prev_*) is the caller's: :class:`OuterAbcState` or :func:`outer_abc_sequence`.
    """
    if new_subject:
        # Step 3: c := c', a from Eq. 4.8.
        return math.sqrt(b * b + cp * cp), cp, BRANCH_NEW
    below, above = params.band
    near = -below <= cp - params.c_rest <= above
    if near and b > prev_b:
        # 3(a): lips dropping; width decreases (prev_b - b < 0), c from Eq. 4.14.
        a = prev_a + (prev_b - b) / params.width_rate_divisor
        return a, math.sqrt(abs(a * a - b * b)), BRANCH_DROP
    if near and b < prev_b:
        # 3(b): lips rising; width increases (prev_b - b > 0), c from Eq. 4.14.
        a = prev_a + (prev_b - b) / params.width_rate_divisor
        return a, math.sqrt(abs(a * a - b * b)), BRANCH_RISE
    # 3(c): rounding or stretching while moving up or down.
    c = params.rho * cp + (1.0 - params.rho) * prev_c
    if b < prev_a or cp < params.small_c_prime:
        # ii: horizontal (height < previous width) or round lips: a from Eq. 4.8.
        return math.sqrt(b * b + c * c), c, BRANCH_HORIZONTAL
    # iii: may be vertical: the width follows the height slowly, c from Eq. 4.14.
    a = prev_a - (prev_b - b) / params.width_rate_divisor
    return a, math.sqrt(abs(a * a - b * b)), BRANCH_VERTICAL


def _step_state(state: OuterAbcState, b: float, cp: float, params: OuterAbcParams):
    a, c, branch = outer_abc_step(
        b, cp, state.prev_a, state.prev_b, state.prev_c, state.new_subject, params
    )
    # Step 4: remember this frame's (unlimited) values.
    state.prev_a, state.prev_b, state.prev_c, state.new_subject = a, b, c, False
    return a, c, branch


@dataclass(frozen=True)
class OuterAbcTrack:
    """OUTER_ABC_CALC over a task: arrays (F,) of a, c (Parke units) and branch codes (int8)."""

    a: np.ndarray
    c: np.ndarray
    branch: np.ndarray

    @property
    def branch_labels(self) -> np.ndarray:
        """Branch codes as the thesis's step labels ("3", "3a", "3b", "3c-ii", "3c-iii")."""
        return np.asarray(BRANCH_LABELS, dtype=object)[self.branch]


def outer_abc_sequence(
    b,
    cp,
    *,
    params: OuterAbcParams | None = None,
    state: OuterAbcState | None = None,
) -> OuterAbcTrack:
    """Run OUTER_ABC_CALC over consecutive frames.

    Parameters
    ----------
    b, cp : array (F,)
        Outer height and c' per frame.
    params : OuterAbcParams, optional
    state : OuterAbcState, optional
        Carried state; a fresh one (NewSubject) when omitted. It is updated in place, so a task
        can be processed in chunks with the same result as in one call.

    Returns
    -------
    OuterAbcTrack
    """
    params = params or OuterAbcParams()
    state = state if state is not None else OuterAbcState()
    b_list = np.asarray(b, dtype=np.float64).tolist()
    cp_list = np.asarray(cp, dtype=np.float64).tolist()
    if len(b_list) != len(cp_list):
        raise ValueError(f"b and cp differ in length: {len(b_list)} != {len(cp_list)}")
    n = len(b_list)
    a_out = [0.0] * n
    c_out = [0.0] * n
    br_out = [0] * n
    pa, pb, pc, new = state.prev_a, state.prev_b, state.prev_c, state.new_subject
    step = outer_abc_step
    for i in range(n):
        bi = b_list[i]
        a, c, br = step(bi, cp_list[i], pa, pb, pc, new, params)
        a_out[i] = a
        c_out[i] = c
        br_out[i] = br
        pa, pb, pc, new = a, bi, c, False  # step 4
    state.prev_a, state.prev_b, state.prev_c, state.new_subject = pa, pb, pc, new
    return OuterAbcTrack(
        a=np.asarray(a_out, dtype=np.float64),
        c=np.asarray(c_out, dtype=np.float64),
        branch=np.asarray(br_out, dtype=np.int8),
    )


def limit_abc(
    a,
    c,
    *,
    a_min: float | None = None,
    a_max: float | None = None,
    c_limit: float = K.C_LIMIT,
) -> tuple[np.ndarray, np.ndarray]:
    """Step 7 of LIP MOVEMENT: limits on the outer a and c (Parke units).

    ``a`` is clipped to [a_min, a_max] (the drawn width; by default ``A_MIN``, ``A_MAX``, read
    at the call) and ``c`` to [0, c_limit] (how far the corner is stretched). The orientation stays OUTER_ABC_CALC's own (height against its
    unlimited width): c passes through 0 at that switch, so the corner does not jump there,
    whereas judging it against the clipped width would switch it wherever a limit binds.

    The limits act on what is drawn; OUTER_ABC_CALC's state keeps its own values (its step 4
    runs before step 7 of LIP MOVEMENT).

    Returns
    -------
    (a, c) : arrays (F,)
    """
    a_min = K.A_MIN if a_min is None else a_min
    a_max = K.A_MAX if a_max is None else a_max
    return (
        np.clip(np.asarray(a, dtype=np.float64), a_min, a_max),
        np.clip(np.asarray(c, dtype=np.float64), 0.0, c_limit),
    )


def mid_inner_abc(upper_z, lower_z, corner_y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Algorithm MID_INNER_ABC_CALC (Figure 4.19) for the middle and inner outlines.

    Parameters
    ----------
    upper_z, lower_z : array (F,)
        z of the upper and lower lip points (middle: 64 and the midpoint of 52 and 55;
        inner: 61 and 58).
    corner_y : array (F,)
        y of the corner point (middle: vertex 300; inner: vertex 287).

    Returns
    -------
    (a, b, c) : arrays (F,)
        ``b = (upper_z - lower_z) / 2`` (signed: negative when the points cross), ``a = corner_y``
        and c from Eq. 4.14 using the height |b|.
    """
    b = (np.asarray(upper_z, dtype=np.float64) - np.asarray(lower_z, dtype=np.float64)) / 2.0
    a = np.asarray(corner_y, dtype=np.float64)
    return a, b, focal_c(a, np.abs(b))


def ellipse_z(y, a, b, k, *, upper: bool) -> np.ndarray:
    """Equation 4.16: z of the outline at horizontal position y.

    ``z = +/- sqrt(b^2 - y^2 b^2 / a^2) + k``, written ``k +/- b sqrt(1 - (y/a)^2)`` with a
    signed b so that the outline passes through its upper point at y = 0 (z = k + b) and its
    lower point (z = k - b) even when those points cross. ``y`` beyond ``a`` (vertex 70 placed
    past a) gives z = k.

    Parameters
    ----------
    y : array broadcastable with a, b, k
        Horizontal positions (Parke units, >= 0).
    a, b, k : array (F,) or (F, 1)
        Half-width (> 0), signed half-height, and centre height.
    upper : bool
        Upper (+) or lower (-) lip.
    """
    y = np.asarray(y, dtype=np.float64)
    a = np.asarray(a, dtype=np.float64)
    r = np.clip(y / a, 0.0, 1.0)
    s = np.sqrt(1.0 - r * r) * b
    return k + s if upper else k - s
