"""The rigs: a BPM library's stones assembled in a container and loaded cyclically, with
per-cycle records — the box test (thesis 4.1-4.2.3) and the cyclic biaxial test (the 2D
analogue of the cyclic triaxial test of the measured data).

The kit: ``deposition`` (placing, dropping, settling stones in any container), ``base``
(Rig: Simulation + layout + parameters, save/load), ``cyclic`` (CyclicRun: the event loop
over the controllers that run inside the engine's loop, ``ballaststudy.dem.control``;
records, behaviours, checkpoints), ``records`` / ``output`` (metrics.nc, figures), ``vtk``
(ParaView snapshots), ``library`` (BPM.nc reader, synthetic stand-in).
The box: ``params`` (RigParams), ``box`` (BoxRig), ``assembly`` (drop, tamping, container
reset, plate, loading ball, relaxation), ``loading`` (LoadingRun: static servo, cyclic
profile). The biaxial test: the package ``biaxial``, in the same rooms (``params``,
``specimen``, ``assembly``, ``loading``, ``output``; BiaxialParams, BiaxialRig,
assemble_biaxial, BiaxialRun). ``cli``: ``ballaststudy case assemble|run``.
"""
from .assembly import assemble
from .biaxial import BiaxialParams, BiaxialRig, BiaxialRun, assemble_biaxial
from .box import BoxRig
from .library import Library, load_library, synthetic_library
from .loading import LoadingRun
from .params import RigParams, case_seed

__all__ = ["assemble", "BoxRig", "Library", "load_library", "synthetic_library",
           "LoadingRun", "RigParams", "case_seed", "BiaxialParams", "BiaxialRig",
           "BiaxialRun", "assemble_biaxial"]
