"""What a modifier is: a named change to an assembled rig with declared parameters (name,
long name, units, bounds), what it sets on the rig before loading (``configure``), and the
end-of-cycle hooks it needs (``hook``). Whatever it changes lives in the engine state
(coefficients, bond strengths) or the rig's parameters, so checkpoints carry it and a
resumed run only needs its hooks again."""
from dataclasses import dataclass
from typing import Callable


class ModifierError(ValueError):
    """A modifier that cannot act on this rig (``name``: the modifier's)."""

    def __init__(self, name, message):
        super().__init__(f"modifier {name}: {message}")
        self.name, self.reason = name, message


@dataclass(frozen=True)
class ModifierParameter:
    name: str
    long_name: str
    units: str
    low: float                   # physical range: above low (strictly if open_low), up to high
    high: float
    open_low: bool = False

    def admits(self, value):
        return (value > self.low if self.open_low else value >= self.low) and value <= self.high

    def range_text(self):
        return f"{'>' if self.open_low else '>='} {self.low:g} and <= {self.high:g}"


@dataclass(frozen=True)
class Modifier:
    name: str
    mechanism: str
    parameters: tuple                   # ModifierParameter
    configure: Callable = None          # (rig, values, covariates) before the loading run
    hook: Callable = None               # (values) -> end-of-cycle hook(run, cycle)
    covariate: str = None               # acts only through this declared covariate (else everywhere)
    current: Callable = None            # (rig) -> {name: value} an assembled rig has untouched
    role: str = "effect"                # "material": a Table 4.2 parameter a calibration varies;
                                        # "effect": a mechanism the loop may add
    needs_rolling: bool = False         # sets a rolling coefficient: the rig must be assembled
                                        # with the law's rolling sub-model (rolling_resistance)
    rig_settings: tuple = ()            # ((rig parameter, value), ...) it sets whatever its
                                        # values, before ``configure`` (what a cache key sees)
    needs_flat_joints: bool = False     # acts on the stones' flat joints: a stone model
                                        # without them (rigid) cannot take it
    needs_splitting: bool = False       # acts on the strengths of stones that split: rigid
                                        # stones with splitting on
    off: Callable = None                # (material values {name: value}) -> {parameter: the value at
                                        # which the effect is off, the plain model}; None: no value
                                        # is (rate: its real-time mode is itself a change)

    @property
    def hook_only(self):
        """Acts only through its end-of-cycle hooks: a run is the run without it up to
        the end of the first loading (cycle 0), where its hook first acts."""
        return self.hook is not None and self.configure is None and not self.rig_settings

    def testable(self, conditions_list):
        """Whether the tests can show it: one that acts only through a covariate needs a
        test declaring it nonzero (its runs would equal the plain model's)."""
        return self.covariate is None or any(
            covariate((c or {}).get("covariates"), self.covariate) != 0 for c in conditions_list)

    def check(self, values):
        """{name: value} complete and within the bounds, else ValueError."""
        names = [p.name for p in self.parameters]
        if sorted(values) != sorted(names):
            raise ValueError(f"modifier {self.name}: parameters {sorted(values)}, expected {names}")
        for p in self.parameters:
            if not p.admits(values[p.name]):
                raise ValueError(f"modifier {self.name}: {p.name} = {values[p.name]:g} outside "
                                 f"[{p.low:g}, {p.high:g}]")

    def hooks(self, values):
        """The end-of-cycle hooks it needs with ``values`` (attach them again on resume)."""
        self.check(values)
        return [self.hook(values)] if self.hook else []

    def apply(self, rig, values, covariates=None):
        """Set it with ``values`` on an assembled (not yet loaded) rig under a test's
        declared covariates."""
        self.check(values)
        self.set_rig(rig.params)
        if self.configure:
            self.configure(rig, values, covariates or {})

    def set_rig(self, params):
        """Its ``rig_settings`` on rig parameters (the params object, changed in place)."""
        for name, value in self.rig_settings:
            setattr(params, name, value)


# covariates a modifier reads: (units, lowest, highest)
COVARIATES = {"VCI": ("%", 0.0, 100.0)}


def covariate(covariates, name, absent=0.0):
    """A declared covariate's value from a test's covariates (its conditions' ``covariates``),
    ``absent`` if the test does not declare it; ValueError if its units or range are not
    the ones the modifiers assume (VCI: % of the void volume, 0-100)."""
    cov = (covariates or {}).get(name)
    if not cov:
        return float(absent)
    units, low, high = COVARIATES[name]
    if cov.get("units") != units or not low <= float(cov["value"]) <= high:
        raise ValueError(f"covariate {name} = {cov['value']} {cov.get('units')}: the modifiers read it "
                         f"in {units}, {low:g}-{high:g}")
    return float(cov["value"])
