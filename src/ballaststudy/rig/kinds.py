"""The rig kinds a case can be (``box``: thesis 4.1-4.2; ``biaxial``: the 2D cyclic
triaxial test) - one place that knows each kind's classes, its parameters from the config
and which measured tests it runs."""
from .biaxial import BiaxialParams, BiaxialRig, BiaxialRun, write_biaxial_outputs
from .box import BoxRig
from .loading import LoadingRun
from .output import write_outputs
from .params import RigParams

KINDS = ("box", "biaxial")
RUNS_TESTS = {"box": ("box",), "biaxial": ("triaxial", "biaxial")}   # measured test's rig


def kind_of(assembled):
    """The kind of an assembled case's dataset (files from before the biaxial rig: box)."""
    return str(assembled.attrs.get("rig_kind", "box"))


def kind_for_test(test_rig):
    """The rig kind that runs a measured test of rig ``test_rig`` (its conditions' ``rig``)."""
    return next(k for k, tests in RUNS_TESTS.items() if test_rig in tests)


def rig_classes(kind):
    """(Rig class, run class, output writer) of a rig kind."""
    if kind == "biaxial":
        return BiaxialRig, BiaxialRun, write_biaxial_outputs
    return BoxRig, LoadingRun, write_outputs


def params_class(kind):
    if kind == "biaxial":
        return BiaxialParams
    return RigParams


def params_from_config(kind, rig_config):
    """The kind's parameters from the config's ``rig`` section."""
    return params_class(kind).from_config(rig_config or {})

