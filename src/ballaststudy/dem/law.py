"""Contact laws as compositions of registered sub-models (Python side).

Every sub-model declares its kind, its kernel code (submodels.py), the names of its
coefficients (columns of the material-pair table), the width of its history (reset when
the contact opens) and the names of its persistent per-contact state. A ``ContactLaw``
picks one sub-model per kind and lays the columns out; the kernels see only the integer
``layout()`` and the table. A new law is a kernel branch in submodels.py plus one
``register`` call here.
"""
from dataclasses import dataclass

from . import submodels as K

KINDS = ("normal", "damping", "tangential", "rolling")


@dataclass(frozen=True)
class SubModel:
    kind: str
    name: str
    code: int
    coefficients: tuple = ()     # column names, with units in the doc below
    history: int = 0             # history columns (reset when the contact opens)
    state: tuple = ()            # persistent per-contact state (names)
    doc: str = ""


SUBMODELS = {}


def register(sm):
    SUBMODELS[(sm.kind, sm.name)] = sm
    return sm


register(SubModel("normal", "linear_pfc", K.NORMAL_LINEAR_PFC, ("E",),
                  doc="k_n = A E*/L, A = 2 min(R) t, L = R1 + R2 (facet: R); E* [Pa]"))
register(SubModel("normal", "hooke", K.NORMAL_HOOKE, ("kn",),
                  doc="constant k_n [N/m], contact arm R (LAMMPS gran/hooke)"))
register(SubModel("damping", "pfc_dashpot", K.DAMPING_PFC_DASHPOT, ("beta_n", "no_tension"),
                  doc="-2 beta_n sqrt(m_c k_n) v_n; no_tension (0/1) clamps the total at 0"))
register(SubModel("damping", "mass_viscous", K.DAMPING_MASS_VISCOUS, ("gamma_n",),
                  doc="-m_eff gamma_n v_n, gamma_n [1/s] (LAMMPS dampflag 1)"))
register(SubModel("tangential", "pfc_incremental", K.TANGENTIAL_PFC_INCREMENTAL,
                  ("kappa", "mu", "beta_s"), history=1, state=("slip_work",),
                  doc="incremental F_s, k_s = k_n/kappa*, |F_s| <= mu F_n^linear, "
                      "dashpot beta_s while sticking; slip_work [J]"))
register(SubModel("tangential", "lammps_history", K.TANGENTIAL_LAMMPS_HISTORY,
                  ("kt", "gamma_t", "mu"), history=2, state=("slip_work",),
                  doc="shear displacement xi, kt [N/m], gamma_t [1/s], |F_t| <= mu |F_n|"))
register(SubModel("rolling", "none", K.ROLLING_NONE, doc="no rolling resistance"))
register(SubModel("rolling", "epsd", K.ROLLING_EPSD, ("mu_r", "kr_ratio", "eta_r"), history=1,
                  state=("rolling_work",),
                  doc="Ai et al. (2011) type C: k_r = kr_ratio k_s R_r^2, |M_r| <= mu_r R_r F_n, "
                      "dashpot eta_r while elastic; rolling_work [J]"))


class ContactLaw:
    """One sub-model per kind, e.g. ``ContactLaw.pfc(rolling="epsd")``."""

    def __init__(self, normal="linear_pfc", damping="pfc_dashpot",
                 tangential="pfc_incremental", rolling="none"):
        names = dict(normal=normal, damping=damping, tangential=tangential, rolling=rolling)
        self.parts = []
        for kind in KINDS:
            key = (kind, names[kind])
            if key not in SUBMODELS:
                known = sorted(n for k, n in SUBMODELS if k == kind)
                raise ValueError(f"unknown {kind} sub-model {names[kind]!r} (known: {known})")
            self.parts.append(SUBMODELS[key])
        for sm in self.parts[:2]:
            if sm.history or sm.state:
                raise ValueError(f"{sm.kind} sub-models own no history or state (got {sm.name})")
        cols = [c for sm in self.parts for c in sm.coefficients]
        if len(cols) > K.NCOEF:
            raise ValueError(f"contact law {names}: {len(cols)} coefficients, at most {K.NCOEF}")
        if len(set(cols)) != len(cols):
            raise ValueError(f"sub-models of one law share a coefficient name: {cols}")
        self.coefficients = tuple(cols)
        self.state_names = tuple(s for sm in self.parts for s in sm.state)
        self.history_width = sum(sm.history for sm in self.parts)

    @classmethod
    def pfc(cls, rolling="none"):
        """PFC linear model with dashpots (the engine's law, physics spec "LC")."""
        return cls("linear_pfc", "pfc_dashpot", "pfc_incremental", rolling)

    @classmethod
    def hooke(cls, rolling="none"):
        """LAMMPS gran/hooke/history with dampflag 1 (the settle2d benchmark's law)."""
        return cls("hooke", "mass_viscous", "lammps_history", rolling)

    @classmethod
    def from_names(cls, names):
        return cls(*names)

    @property
    def names(self):
        return tuple(sm.name for sm in self.parts)

    @property
    def width(self):
        """Columns of the per-contact array: history, then persistent state."""
        return self.history_width + len(self.state_names)

    def layout(self):
        """The packed int the kernels read (submodels.py: codes and block offsets, 4 bits
        each), passed to them as a numba literal so that each law compiles to its own code."""
        fields = [0] * K.N_FIELDS
        c = h = s = 0
        first = {}
        for k, sm in enumerate(self.parts):
            fields[k] = sm.code
            first[sm.kind] = (c, h, s)
            c += len(sm.coefficients)
            h += sm.history
            s += len(sm.state)
        for kind, (cf, hf, sf) in (("damping", (K.C_DAMPING, None, None)),
                                   ("tangential", (K.C_TANGENTIAL, K.H_TANGENTIAL, K.S_TANGENTIAL)),
                                   ("rolling", (K.C_ROLLING, K.H_ROLLING, K.S_ROLLING))):
            fields[cf] = first[kind][0]
            if hf is not None:
                fields[hf], fields[sf] = first[kind][1:]
        fields[K.WIDTH] = self.history_width
        key = 0
        for k, v in enumerate(fields):
            if not 0 <= v < 16:
                raise ValueError(f"contact law {self.names}: layout field {k} = {v} "
                                 "does not fit in 4 bits")
            key |= v << (4 * k)
        return key

    def history_column(self, kind):
        """First column of ``kind``'s history in the per-contact array (Pairs.hist): the
        history blocks follow the order of the kinds, the state columns come after them."""
        k = KINDS.index(kind)
        return sum(sm.history for sm in self.parts[:k])

    def row(self, coefficients):
        """Table row from a dict of coefficients; every column of the law must be given."""
        missing = [c for c in self.coefficients if c not in coefficients]
        if missing:
            raise ValueError(f"contact law {self.names} needs coefficients {missing}")
        row = [float(coefficients[c]) for c in self.coefficients]
        return row + [0.0] * (K.NCOEF - len(row))       # the table is NCOEF wide

    def column(self, name):
        if name not in self.coefficients:
            raise KeyError(f"contact law {self.names} has no coefficient {name!r} "
                           f"(has {list(self.coefficients)})")
        return self.coefficients.index(name)

    def __repr__(self):
        return "ContactLaw(" + ", ".join(f"{k}={n!r}" for k, n in zip(KINDS, self.names)) + ")"
