"""The cyclic biaxial test: the 2D analogue of the cyclic triaxial test on which the public
measured ballast data are taken (a 300 x 600 mm cylinder under a confining pressure p and
a cyclic deviator stress q). Built on the kit: deposition.py places and drops the stones,
dem.control runs the servos inside the engine's loop, cyclic.py keeps the records.

The specimen is a rectangle of bonded stones between a bottom platen, a top platen and two
frictionless sides: rigid side walls (``membrane_segments`` 1), or a flexible membrane, a
chain of ``membrane_segments`` segments per side, each under its own stress servo, so the
specimen bulges as a real one does (the segments' heights follow the platens: each spans
1/n of the specimen height). Stages:
1. deposition in a tall box of the specimen's width; balls above the specimen height cut;
2. isotropic consolidation: three stress servos (left, right, top) hold p until the
   window means of all three are within ``consolidation_tolerance`` of p;
3. cyclic loading: the sides keep p; the axial stress sigma_1 = p + q runs between
   p + q_min and p + q_max as a sinusoid in simulated time. ``load_control``
   applied_force: both are loads on bodies (stress boundaries), the top platen of
   platen_mass_ratio x the specimen's mass, the sides of its mass per area; servo: stress
   servos move the walls, the platen's with a feed-forward from the compliance it
   measures per branch and bounds adapted cycle by cycle. Real time: at the test's frequency f (a
   cycle lasts 1/f), true masses but for realtime_added_inertia_max of density scaling;
   quasi-static: at the largest f the inertial-number and stress-wave bounds allow
   (``inertial``), with density scaling (loading_dt_factor), its first loading the
   bound-to-bound profile at the configured platen speeds. Cycle 0 is the first loading
   from p to p + q_max and the unloading to p + q_min: load cycle N = 1 of a laboratory
   test.
2D stresses are forces per boundary length per thickness t (sigma = F / (L t)); strains are
compression positive from the end of consolidation: axial 1 - H/H0, volumetric (area)
1 - W H / (W0 H0), H and W between the walls' faces.

One concept per module, as the box rig's files: ``params`` (BiaxialParams), ``specimen``
(BiaxialLayout, BiaxialRig: its walls, size, stresses; the membrane kept spanning the
platens), ``assembly`` (assemble_biaxial), ``loading`` (the sensors and controllers, the
consolidation, hold and cycling phases: BiaxialRun), ``output`` (metrics.nc and figures).
The behaviours per cycle are ``ballaststudy.metrics.biaxial.compute_biaxial_cycle``.
"""
from .assembly import assemble_biaxial, build_specimen, membrane_groups, wall_friction
from .loading import (AXIAL, CYCLE_FIELDS, HEIGHT, LEFT, RIGHT, X_LEFT, X_RIGHT, BiaxialRun,
                      BiaxialState, ControllerIds, biaxial_control, segment_scales)
from .output import CHANNEL_UNITS, write_biaxial_outputs
from .params import KPA, BiaxialParams
from .specimen import MEMBRANE, PLATEN, BiaxialLayout, BiaxialRig, place_membrane

__all__ = ["assemble_biaxial", "build_specimen", "membrane_groups", "wall_friction", "AXIAL",
           "CYCLE_FIELDS", "HEIGHT", "LEFT", "RIGHT", "X_LEFT", "X_RIGHT", "BiaxialRun",
           "BiaxialState", "ControllerIds", "biaxial_control", "segment_scales",
           "CHANNEL_UNITS", "write_biaxial_outputs", "KPA", "BiaxialParams", "MEMBRANE",
           "PLATEN", "BiaxialLayout", "BiaxialRig", "place_membrane"]
