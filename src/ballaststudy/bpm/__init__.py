"""Bonded-particle models (BPMs) of the 2D stone profiles (thesis 4.2.1, Wang 2018).

For each stone of a form database: walls along its 2D profile polygon, balls thrown in,
relaxed with the linear contact model until the average force ratio < 8e-3, walls removed,
flat joints installed between balls closer than g_i = 0.4 * R_small, 1000 cycles relaxed,
saved. Many stones are built side by side in one engine simulation (see ``build``).
``ballaststudy bpm build FORMS.nc --out BPM.nc [--config config/config.yaml]``.

Library format (``BPM.nc``, netCDF4, CF contiguous ragged arrays; SI units)
--------------------------------------------------------------------------
Dimensions ``stone``, ``ball``, ``bond``. Stone k's balls are rows
``sum(ball_count[:k]) ... + ball_count[k]`` of the ``ball`` variables, its bonds likewise
with ``bond_count`` (``stone_balls(ds, k)`` does this).

per stone
    ``form_index`` (int32) index of the stone in the forms file;
    ``material`` (int8, flag_values 0 1, flag_meanings "hard soft");
    ``ball_count``, ``bond_count`` (int32, ``sample_dimension`` "ball" / "bond");
    ``profile_area`` [m2] (copied), ``ball_area`` [m2] sum of pi r^2,
    ``mass_2d`` [kg] rho * sum(pi r^2) * t (PFC2D, per thickness t; rho of Table 4.2),
    ``density`` [kg m-3]; ``sieve_group_lower``, ``sieve_group_upper``, ``a``, ``b``, ``c`` [m]
    (copied from the form); ``min_radius_used``, ``max_radius_used`` [m];
    ``radius_scale`` (factor on the configured radius range) and ``size_policy`` (int8,
    0 default_range, 1 scaled_range: a small stone got a smaller range so that it holds
    ``min_balls``, 2 below_min_at_floor: even at the floor of the scale it holds fewer);
    ``balls_removed`` (deleted after the relaxation: not bonded to the stone's main
    cluster, or centre outside the polygon); ``force_ratio`` reached and ``relax_cycles``;
    ``ball_centroid_x``, ``ball_centroid_y`` [m] where the balls' centroid lies in the
    profile frame of the forms file (profile centroid = origin; x along the profile's a).
per ball
    ``ball_x``, ``ball_y`` [m] relative to the stone's ball centroid (area-weighted, sum of
    r^2 x / sum of r^2 = 0), in the profile frame; ``ball_radius`` [m].
per bond (installed flat joints, all elements bonded)
    ``bond_i``, ``bond_j`` (int32) ball indices LOCAL to the stone (0 .. ball_count-1),
    i < j; ``bond_gap`` [m] surface gap d - R_i - R_j at the saved positions (negative =
    overlap) = the joint's bonded reference state (g_0 = 0). Every gap < 0.4 * min(R_i, R_j).
attributes
    ``database``, ``thickness_m``, ``radius_min_m``, ``radius_max_m``, ``porosity``,
    ``min_balls``, ``radius_scale_floor``; ``materials_json`` (keys ``hard``/``soft``:
    density, flat_joint {E*, kappa*, sigma_c, c, phi, mu, installation_gap_factor, lambda,
    n_elements, ...}, linear_contact {E*, kappa*, mu}, packing_contact; plus ``F_str_co``
    and how it is applied: as Table 4.2 prints it, i.e. on the hard-rock sigma_c and c);
    relaxation statistics ``force_ratio_limit``, ``force_ratio_max``, ``force_ratio_mean``,
    ``stones_not_converged``, ``relax_cycles_max``, ``relax_cycles_mean``,
    ``bonded_cycles``, ``bonds_broken_in_relaxation``; ``max_stones``, ``stone_selection``,
    ``bpm_params`` (JSON), ``seed``, ``provenance`` (JSON, also in ``BPM.nc.prov.json``).

Use ``load_library(path)`` and ``stone_balls(ds, k)`` -> (x, y, r, bond_i, bond_j, material).
"""
from .library import build_library, load_library, select_stones, stone_balls
from .params import BpmParams

__all__ = ["BpmParams", "build_library", "load_library", "select_stones", "stone_balls"]
