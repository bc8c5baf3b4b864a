"""The box-test rig (thesis 4.1-4.2.3): a BPM library's stones assembled in the box and
loaded, statically (10/20/30 kN) then cyclically (15-45 kN), with per-cycle records.

Modules: ``library`` (BPM.nc reader, synthetic stand-in), ``params`` (the ``rig:``
config), ``box`` (BoxRig: Simulation + layout, save/load), ``assembly`` (drop, tamping,
container reset, plate, loading ball, relaxation), ``loading`` (LoadingRun: servo, cyclic
reversal, records, checkpoints), ``records`` / ``output`` (metrics.nc, figures),
``vtk`` (ParaView snapshots), ``cli`` (``ballaststudy case assemble|run``).
Rig operations are "fix"-like steps between engine runs of ``ballaststudy.dem``.
"""
from .assembly import assemble
from .box import BoxRig
from .library import Library, load_library, synthetic_library
from .loading import LoadingRun
from .params import RigParams, case_seed

__all__ = ["assemble", "BoxRig", "Library", "load_library", "synthetic_library",
           "LoadingRun", "RigParams", "case_seed"]
