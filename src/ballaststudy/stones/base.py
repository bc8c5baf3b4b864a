"""What a stone model answers (stones/__init__.py): the stones made in the engine, their
topology (which balls hold together now), and what can break and what broke."""
from abc import ABC, abstractmethod

from ..dem.fragments import fragments as label_fragments


class StoneModelError(ValueError):
    """An unknown model, or a model asked for what it cannot do."""


class StoneModel(ABC):
    """The interface: a model defines every abstract method (one that does not cannot be
    made); ``name`` is its registry key."""
    name = ""
    description = ""
    has_flat_joints = False         # what a modifier acting on flat joints needs
    break_modes = ()                # the modes of its breakage records (metrics.breakage)
    gpu_batch = False               # the GPU batch (dem/gpu) steps its stones
    can_split = False               # its stones can split (make's ``splitting``)

    @abstractmethod
    def make(self, sim, stone_balls, splitting=None):
        """Turn the assembled (bonded) stones of balls ``stone_balls`` into this model's
        (``splitting``: how they split, for a model whose stones split)."""

    @abstractmethod
    def topology(self, sim):
        """(i, j, intact): links between balls whose connected components are the
        fragments (the stones as they are now)."""

    @abstractmethod
    def breakable_units(self, sim):
        """How many units can break now (bonds, stones)."""

    @abstractmethod
    def elements_per_unit(self, sim):
        """Breakage records a unit can give: units x this = the breakage rate's
        denominator."""

    @abstractmethod
    def breakages(self, sim):
        """The breakage record since the start (Simulation.breakages' columns)."""

    def n_breakages(self, sim):
        """Rows of ``breakages`` so far: where a run's own records begin."""
        return int(len(self.breakages(sim)["step"]))

    def fragments(self, sim, n_balls):
        """Fragment label of balls 0..n_balls-1 (-1: dead), numbered by lowest ball id."""
        i, j, intact = self.topology(sim)
        alive = sim.balls.alive[:n_balls] == 1
        keep = (i < n_balls) & (j < n_balls)
        return label_fragments(n_balls, i[keep], j[keep], intact[keep], alive)[1]
