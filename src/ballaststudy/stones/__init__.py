"""Stone models: how a stone the forms made is modelled in the engine, one module a model
behind one small interface (``StoneModel``), chosen by name as LAMMPS chooses a style.
Rigs and metrics ask the model (``rig.stones``) and never test which one it is.

    bonded  the thesis' BPM: the stone's balls glued by flat joints, breaking bond by bond
    rigid   the same balls as the pebbles of one rigid clump per stone (no internal
            springs: the timestep is set by the contacts between stones)

Every specimen is assembled with bonded stones (the assembly's drop strengthens the bonds
so nothing breaks); ``make`` turns the assembled stones into the chosen model's, so both
models load the very same specimens."""
from .base import StoneModel, StoneModelError
from .bonded import BondedStones
from .rigid import RigidStones

STONE_MODELS = {m.name: m for m in (BondedStones(), RigidStones())}
DEFAULT = "bonded"


def stone_model(name):
    """The model registered as ``name``; StoneModelError (naming the allowed ones) else."""
    try:
        return STONE_MODELS[name]
    except (KeyError, TypeError):
        raise StoneModelError(f"unknown stone model {name!r}; allowed: "
                              f"{', '.join(STONE_MODELS)}") from None


__all__ = ["STONE_MODELS", "DEFAULT", "StoneModel", "StoneModelError", "stone_model"]
