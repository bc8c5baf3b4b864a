"""Calibration of model parameters against measured curves (thesis 4.3): a Gaussian-process surrogate of the ensemble-mean curve, Bayesian posterior, sequential design."""
