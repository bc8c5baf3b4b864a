"""Breakage rate (thesis 4.5.1, eqs. 4.6-4.8, l. 1040-1048).

BR_T = FJ_T / FJ_Total, BR_S = FJ_S / FJ_Total, BR = BR_T + BR_S, where FJ_T / FJ_S are
the flat-joint bonds broken in tension / shear and FJ_Total all flat-joint bonds. Rigid
stones (stones.rigid) break by splits: a record is a split, the total the stones, and BR
is splits per stone. The
equations define plain ratios, so they are returned as fractions (units "1"); the thesis'
figures quote them in percent ("smaller than 1%", l. 1228) - multiply by 100 to plot.

Neither rate compares the two models (a bond is not a stone), so both also give
``broken_mass_share``: the share of the stones' mass no longer in the largest piece of the
stone (the fragment when loading began) it belonged to - what a sieve sees, in the same
units for either model (ball masses: the stones' materials differ in density).

The engine logs one record per broken flat-joint *element*. The thesis uses N_r = 1
element per bond (Table 4.2), so a record is a broken bond; for N_r > 1 pass
``n_elements_per_bond`` and the denominator becomes all installed elements.
"""
import numpy as np

MODE_TENSION = 1   # same codes as ballaststudy.dem.bonds
MODE_SHEAR = 2
MODE_SPLIT = 3     # a rigid stone split in two (dem/crushing.py; stones.rigid)
BREAK_MODE_CODES = {"tension": MODE_TENSION, "shear": MODE_SHEAR, "split": MODE_SPLIT}


def mode_codes(modes):
    """The codes of breakage modes given by name ('tension', 'shear', 'split')."""
    return _modes(np.asarray(modes, dtype=object)).astype(np.int8)


def _modes(mode):
    m = np.asarray(mode)
    if m.dtype.kind in "USO":
        try:
            m = np.array([BREAK_MODE_CODES[str(s).lower()] for s in m], dtype=np.int64)
        except KeyError as err:
            raise ValueError(f"breakage mode {err} is not 'tension', 'shear' or 'split'") from None
    m = m.astype(np.int64)
    bad = ~np.isin(m, (MODE_TENSION, MODE_SHEAR, MODE_SPLIT))
    if bad.any():
        raise ValueError(f"breakage mode {m[bad][0]} is not 1 (tension), 2 (shear) or 3 (split)")
    return m


def breakage_rate(break_mode, break_step, n_bonds_installed, cycle_bounds, n_elements_per_bond=1):
    """Cumulative breakage rates at the end of each cycle and breakages per cycle.

    break_mode: (r,) per breakage record, 1/'tension', 2/'shear' or 3/'split' (a rigid
        stone split: its unit is the stone, n_bonds_installed then counts stones).
    break_step: (r,) calculation step of each record.
    n_bonds_installed: flat-joint bonds installed when the stones were built (FJ_Total
        for N_r = 1).
    cycle_bounds: (K+1,) steps; cycle k spans cycle_bounds[k] <= step < cycle_bounds[k+1].
    Breakages before cycle_bounds[0] (assembly, static pre-loading) count in the
    cumulative rates - a bond broken then is broken - but in no cycle's count.

    Returns dict of (K,) arrays: breakage_rate_tension, breakage_rate_shear,
    breakage_rate (fractions: tension + shear + split), breakages_per_cycle, broken_tension,
    broken_shear (counts; a rigid stone's splits are breakage_rate's and breakages_per_cycle's).
    """
    mode = _modes(break_mode)
    step = np.asarray(break_step, dtype=np.int64)
    if mode.shape != step.shape:
        raise ValueError(f"break_mode {mode.shape} and break_step {step.shape} differ in length")
    bounds = np.asarray(cycle_bounds, dtype=np.int64)
    if bounds.ndim != 1 or bounds.size < 1 or np.any(np.diff(bounds) < 0):
        raise ValueError("cycle_bounds must be a non-decreasing 1D array of steps")
    total = int(n_bonds_installed) * int(n_elements_per_bond)
    if total <= 0:
        raise ValueError(f"n_bonds_installed * n_elements_per_bond = {total}; must be > 0")
    ends = bounds[1:]
    t_steps = np.sort(step[mode == MODE_TENSION])
    s_steps = np.sort(step[mode == MODE_SHEAR])
    n_t = np.searchsorted(t_steps, ends, side="left")   # records with step < end
    n_s = np.searchsorted(s_steps, ends, side="left")
    n_x = np.searchsorted(np.sort(step[mode == MODE_SPLIT]), ends, side="left")
    all_steps = np.sort(step)
    cum = np.searchsorted(all_steps, bounds, side="left")
    return dict(breakage_rate_tension=n_t / total, breakage_rate_shear=n_s / total,
                breakage_rate=(n_t + n_s + n_x) / total, breakages_per_cycle=np.diff(cum),
                broken_tension=n_t, broken_shear=n_s)


def broken_mass_share(units, labels, mass):
    """Share of the stones' mass no longer in the largest fragment of their unit:
    1 - sum_u max_f M(u, f) / sum_u M(u).

    units: (n,) the fragment each ball was in when loading began (-1: no stone ball then).
    labels: (n,) its fragment now (-1: deleted - a rigid stone's fines - or no stone).
    mass: (n,) ball masses [kg] (real, not density-scaled). Returns a fraction (0: every
    stone whole)."""
    units = np.asarray(units, np.int64)
    labels = np.asarray(labels, np.int64)
    mass = np.asarray(mass, float)
    was = units >= 0
    if not was.any() or mass[was].sum() <= 0.0:
        raise ValueError("no stone balls when loading began: the share is undefined")
    n_units = int(units.max()) + 1
    per_unit = np.bincount(units[was], weights=mass[was], minlength=n_units)
    now = was & (labels >= 0)
    u, f, m = units[now], labels[now], mass[now]
    base = max(int(labels.max()), 0) + 1
    piece, idx = np.unique(u * base + f, return_inverse=True)   # one per (unit, fragment now)
    largest = np.zeros(n_units)
    np.maximum.at(largest, piece // base, np.bincount(idx, weights=m))
    # a whole stone's piece sums its balls in the order its unit does: 0 exactly
    return float((per_unit - largest).sum() / per_unit.sum())
