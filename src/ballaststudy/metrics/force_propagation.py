"""Force propagation angle (thesis 4.5.1, eq. 4.9, Fig. 4-16, l. 1050-1059).

The container bottom is 20 equidistant wall segments that measure the vertical force.
On each side of the plate's middle, x90 is the distance from the middle within which 90 %
of that side's bottom force is collected (Steiner et al. [47]: "the 90% of the total
force"). Within a segment the force is taken as uniform, so the cumulative force is
piecewise linear and x90 is interpolated inside the segment where 90 % is reached.

Reference point and direction. The thesis measures the angle at the plate's *bottom middle
point*, not at its corners, because with the corners "the normal definition ... could
result an angle larger than 90 degree" (l. 1059). An angle from the vertical,
atan((x90 - half_width) / depth), can never exceed 90 deg; an angle from the *horizontal*,
atan2(depth, x90 - half_width), does exceed 90 deg exactly when x90 lies inside the plate's
shadow - the low, narrow model's case. So the angle is measured from the horizontal:

    FA_side = atan2(depth, x90_side)        [deg], depth = plate bottom - container bottom
    FA_averaged = (FA_right + FA_left) / 2   (eq. 4.9)

This also matches the thesis' numbers: "about 55 deg" (l. 1285) with depth ~0.18 m and half
width 0.17 m; from the vertical the angle could not exceed atan(0.17/0.18) = 43 deg.

Segment crossing the middle: its force is split between the two sides in proportion to the
length on each side (uniform force per segment; half/half when the middle is its centre).
With 20 equidistant segments and a centred plate the middle is a segment joint and no
split happens.
"""
import math

import numpy as np


def _x_at_fraction(d0, d1, f, fraction):
    """Distance where the cumulative force over pieces [d0, d1] (force f each, uniform
    within a piece) reaches ``fraction`` of the total; NaN if the total is zero."""
    k = (f > 0) & (d1 > d0)
    d0, d1, f = d0[k], d1[k], f[k]
    total = f.sum()
    if total <= 0:
        return math.nan
    o = np.argsort(d0, kind="stable")
    d0, d1, f = d0[o], d1[o], f[o]
    target = fraction * total
    cum = np.cumsum(f)
    i = int(np.searchsorted(cum, target * (1 - 1e-12), side="left"))
    i = min(i, f.size - 1)
    before = cum[i] - f[i]
    return float(d0[i] + (target - before) / f[i] * (d1[i] - d0[i]))


def x90(bottom_force, x_centre, width, x_mid, fraction=0.9):
    """(x90_left, x90_right) [m]: distances from ``x_mid`` collecting ``fraction`` of each
    side's bottom force.

    bottom_force: (s,) downward force carried by each bottom segment [N], compression
        positive (engine: minus the y component of the force balls exert on the segment,
        ``-walls.force[seg, 1]``); negative values (no physical meaning) are set to 0.
    x_centre, width: (s,) segment mid-point x and length [m].
    x_mid: x of the plate's bottom middle point [m].
    """
    f = np.clip(np.asarray(bottom_force, float), 0.0, None)
    xc = np.asarray(x_centre, float)
    w = np.asarray(width, float)
    if not (f.shape == xc.shape == w.shape) or np.any(w <= 0):
        raise ValueError("bottom_force, x_centre and width must have equal shape, width > 0")
    lo, hi = xc - w / 2, xc + w / 2
    # right side: the part [max(lo, x_mid), hi] of each segment, as distances from x_mid
    r0, r1 = np.maximum(lo - x_mid, 0.0), np.maximum(hi - x_mid, 0.0)
    l0, l1 = np.maximum(x_mid - hi, 0.0), np.maximum(x_mid - lo, 0.0)
    fr = f * (r1 - r0) / w
    fl = f * (l1 - l0) / w
    return _x_at_fraction(l0, l1, fl, fraction), _x_at_fraction(r0, r1, fr, fraction)


def force_propagation_angle(bottom_force, x_centre, width, x_mid, plate_bottom_y,
                            container_bottom_y, fraction=0.9):
    """FA_left, FA_right and their mean (eq. 4.9) [deg] with x90 and depth.

    Returns dict: fpa_left, fpa_right, fpa [deg]; x90_left, x90_right, depth [m].
    The angle is measured at the plate's bottom middle point from the horizontal (see the
    module doc): FA = atan2(depth, x90).
    """
    xl, xr = x90(bottom_force, x_centre, width, x_mid, fraction)
    depth = float(plate_bottom_y - container_bottom_y)
    if depth <= 0:
        raise ValueError(f"plate bottom ({plate_bottom_y}) is not above the container bottom ({container_bottom_y})")
    fa_l = math.degrees(math.atan2(depth, xl)) if not math.isnan(xl) else math.nan
    fa_r = math.degrees(math.atan2(depth, xr)) if not math.isnan(xr) else math.nan
    return dict(fpa_left=fa_l, fpa_right=fa_r, fpa=(fa_l + fa_r) / 2,
                x90_left=xl, x90_right=xr, depth=depth)
