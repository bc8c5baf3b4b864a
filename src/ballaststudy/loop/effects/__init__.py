"""Effects the model can gain (issue 14): each a physical mechanism in the DEM with one or
two parameters and a switch (a candidate is on only when the loop runs it), never a
correction added to a curve.

    rate           real-time cyclic loading at the test's frequency (true masses, no local
                   damping) with a viscous contact dashpot: inertia and rate-dependent
                   contact dissipation
    abrasion       asperity wear: the bonds of stone balls in the strong force network lose
                   a share of their strength every cycle, so loaded corners weaken and break
    fouling        clay fines coat the stone-stone contacts: friction falls in proportion to
                   the test's void contamination index VCI
    end_restraint  the platens' friction (rough or lubricated ends, an imperfect bedding of
                   the specimen under the platen), a classic triaxial-test effect

An effect acts on an assembled biaxial rig before its loading run (``switch_on``) and, if it
accumulates over cycles, through an end-of-cycle hook (``hooks``); whatever it changes lives
in the engine state (coefficients, bond strengths) or the rig's parameters, so checkpoints
carry it and a resumed run only needs its hooks again."""
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class EffectParameter:
    name: str
    long_name: str
    units: str
    low: float
    high: float


@dataclass(frozen=True)
class Effect:
    name: str
    mechanism: str
    parameters: tuple                   # EffectParameter
    configure: Callable = None          # (rig, values, conditions) before the loading run
    hook: Callable = None               # (values) -> end-of-cycle hook(run, cycle)
    covariate: str = None               # acts only through this declared covariate (else everywhere)

    def testable(self, conditions_list):
        """Whether the tests can show the effect: one that acts only through a covariate
        needs a test declaring it nonzero (its runs would equal the plain model's)."""
        return self.covariate is None or any(covariate(c, self.covariate) != 0 for c in conditions_list)

    def check(self, values):
        """{name: value} complete and within the bounds, else ValueError."""
        names = [p.name for p in self.parameters]
        if sorted(values) != sorted(names):
            raise ValueError(f"effect {self.name}: parameters {sorted(values)}, expected {names}")
        for p in self.parameters:
            if not p.low <= values[p.name] <= p.high:
                raise ValueError(f"effect {self.name}: {p.name} = {values[p.name]:g} outside "
                                 f"[{p.low:g}, {p.high:g}]")


# covariates an effect reads: (units, lowest, highest)
COVARIATES = {"VCI": ("%", 0.0, 100.0)}


def covariate(conditions, name, absent=0.0):
    """A declared covariate's value from a test's conditions (load_conditions), ``absent``
    if the test does not declare it; ValueError if its units or range are not the ones
    the effects assume (VCI: % of the void volume, 0-100)."""
    cov = (conditions.get("covariates") or {}).get(name)
    if not cov:
        return float(absent)
    units, low, high = COVARIATES[name]
    if cov.get("units") != units or not low <= float(cov["value"]) <= high:
        raise ValueError(f"covariate {name} = {cov['value']} {cov.get('units')}: the effects read it "
                         f"in {units}, {low:g}-{high:g}")
    return float(cov["value"])


def _registry():
    from . import abrasion, end_restraint, fouling, rate
    return {e.name: e for e in (rate.EFFECT, abrasion.EFFECT, fouling.EFFECT, end_restraint.EFFECT)}


EFFECTS = _registry()


def switch_on(name, rig, values, conditions):
    """Effect ``name`` with ``values`` on an assembled rig under a test's conditions."""
    effect = EFFECTS[name]
    effect.check(values)
    if effect.configure:
        effect.configure(rig, values, conditions)


def hooks(name, values):
    """The end-of-cycle hooks effect ``name`` needs (attach them again on resume)."""
    effect = EFFECTS[name]
    effect.check(values)
    return [effect.hook(values)] if effect.hook else []
