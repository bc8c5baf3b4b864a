"""Scenarios: the typed description of one model evaluation (scenario.py), the one registry
of modifiers (modifiers/), the one runner (runner.py) and reading cases back (results.py).
This floor sits just above the rigs; calibration, the loop, the parametric study and
measured_sim build scenarios and read results, and never reach into a rig."""
