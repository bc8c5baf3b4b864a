"""The rig settings of the tests that run the biaxial rig through a config: they check
mechanics and the chain, not the quasi-static rate, so the first loading keeps the speed
they were written for (I = 1.35e-4, ~0.005 m/s on the coarse test stones: the config's
1.5e-5 would take ten times the steps; tests/rig/test_biaxial.py) and consolidation
windows of 1000 steps."""
FAST_LOADING = dict(consolidation_window_steps=1000, first_loading_inertial_number=1.35e-4)
