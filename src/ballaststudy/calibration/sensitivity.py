"""Variance-based global sensitivity (Sobol indices) of a DEM output to the calibration
parameters, from a small space-filling design of parameter sets (thesis 4.4 studies one
parameter at a time, which cannot see interactions).

The sets: a Latin hypercube in the parametric ranges (bayes.initial_design), K cases each. The output of a set is
the mean of its K cases; a Gaussian-process surrogate (bayes.Surrogate, its white-noise term
absorbs the case scatter left in the means) carries them over the box, and SALib
(MIT licence: use and redistribution free, its notice kept) estimates the first-order and
total Sobol indices of the surrogate's mean with Saltelli's sampling and bootstrap 95 %
intervals. The intervals are those of the sampling, not of the surrogate: with few sets the
surrogate's own error dominates, so read the indices as a ranking."""
import numpy as np

from .bayes import Surrogate

BASE_SAMPLES = 1024     # Saltelli base sample: N (d + 2) surrogate evaluations


def sobol_indices(thetas, y, lower, upper, names, seed=0):
    """{name: {S1, S1_conf, ST, ST_conf}} of y (J,) over the sets thetas (J, d)."""
    # deferred: SALib (and what it imports) only when a parametric report asks for indices
    from SALib.analyze import sobol
    from SALib.sample import sobol as saltelli
    y = np.asarray(y, float)
    surrogate = Surrogate(lower, upper, seed).fit(thetas, y[:, None])
    problem = {"num_vars": len(names), "names": list(names),
               "bounds": [[float(a), float(b)] for a, b in zip(lower, upper)]}
    x = saltelli.sample(problem, BASE_SAMPLES, calc_second_order=False, seed=seed)
    mean, _ = surrogate.predict(x)
    si = sobol.analyze(problem, mean[:, 0], calc_second_order=False, seed=seed)
    return {n: {k: float(si[k][i]) for k in ("S1", "S1_conf", "ST", "ST_conf")}
            for i, n in enumerate(names)}
