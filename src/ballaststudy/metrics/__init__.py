"""Behaviours measured once per loading cycle: of the box test (thesis 4.5.1: settlement,
breakage rate, force propagation angle, void ratio, coordination number / ghost particles;
``compute_cycle``) and of the cyclic biaxial test (breakage rate, axial and volumetric
strain, void ratio, coordination number; ``compute_biaxial_cycle``).

Every function here is a compute: a pure function of plain numpy arrays (a snapshot the rig
reads from the engine) that never changes them. SI units throughout.
"""
from .biaxial import BIAXIAL_SNAPSHOT_KEYS, BiaxialGeometry, compute_biaxial_cycle
from .breakage import breakage_rate
from .coordination import container_flags_from_contacts, coordination_numbers, ghost_particles, in_shoulder, touching_container
from .cycle import SNAPSHOT_KEYS, MetricsParams, RigGeometry, compute_cycle
from .force_propagation import force_propagation_angle, x90
from .fragments import fragment_centroids, fragments
from .output import VARIABLES, metrics_dataset, read_metrics, write_metrics
from .settlement import loading_branch_crossing, settlement
from .strain import specimen_strains
from .void_ratio import stone_solid, void_ratio

__all__ = ["BIAXIAL_SNAPSHOT_KEYS", "BiaxialGeometry", "compute_biaxial_cycle", "breakage_rate", "container_flags_from_contacts", "coordination_numbers", "ghost_particles", "in_shoulder",
           "touching_container", "SNAPSHOT_KEYS", "MetricsParams", "RigGeometry", "compute_cycle",
           "force_propagation_angle", "x90", "fragment_centroids", "fragments", "VARIABLES",
           "metrics_dataset", "read_metrics", "write_metrics", "loading_branch_crossing",
           "settlement", "specimen_strains", "stone_solid", "void_ratio"]
