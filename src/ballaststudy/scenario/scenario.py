"""A scenario: one model evaluation, frozen and typed - K assembled specimens of one rig kind
loaded under a test's conditions (already in the rig's parameters) with a list of modifiers
and their values, for a number of cycles. Everything above the rig floor (measured_sim,
calibration, the parametric study, the loop) describes what it wants as scenarios and reads
their metrics files; the runner (runner.py) turns (scenario, specimen) into one.

Its ``key`` is the cache key of its cases: a hash of everything that decides them - the
specimens' content (sha-256 of their files, not their names: specimens re-assembled under
the same names must not reuse old cases), the rig's parameters as the run sees them (the
modifiers' rig settings applied) but those inert under the others (``inert_keys``: a
quasi-static test's frequency), the modifiers in the order they are applied with their
values (12 significant digits), the stone model when it is not the thesis' bonded one and
its splitting law when its stones split, the covariates its modifiers read, the cycles, the metrics
settings, a chaos probe's perturbation when there is one, and the stress mapping's kind and
ratio when one is applied (mapping.py; the bounds it set are in the rig's parameters
already). File names and the conditions file are labels, not part of the key: scenarios of
one key are one run (the loop's quasi-static sets under Sun et al.'s frequency series: one
case for six tests), and its case file carries the first one's labels."""
import hashlib
import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ..provenance.record import sha256_file
from ..rig.kinds import RUNS_TESTS, params_class, params_from_config
from ..schema import ConfigError
from ..stones import DEFAULT, stone_model as stone_model_named
from .mapping import StressMapping, key_of
from .modifiers import MODIFIERS


@lru_cache(maxsize=4096)
def _file_hash(path, mtime_ns, size):
    return sha256_file(path)


def content_hash(path):
    """sha-256 of a file's bytes (read once per process while its mtime and size stay)."""
    st = Path(path).stat()
    return _file_hash(str(path), st.st_mtime_ns, st.st_size)


def _canonical(obj):
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))


def _rounded(values):
    return {k: float(f"{float(v):.12g}") for k, v in sorted(values.items())}


@dataclass(frozen=True)
class Scenario:
    kind: str                       # rig kind (rig.kinds.KINDS)
    specimens: tuple                # paths of the K assembled specimens
    specimen_hashes: tuple          # their content (content_hash): what the key sees
    rig_json: str                   # the rig's parameters, the test's conditions applied
    cycles: int
    modifiers: tuple = ()           # ((name, ((parameter, value), ...)), ...), applied in order
    covariates_json: str = "{}"     # the test's declared covariates (a modifier may read one)
    metrics_json: str = "null"      # the config's metrics section
    conditions_file: str = ""       # the measured test's conditions YAML (a label)
    perturbation_m_s: float = 0.0   # > 0: the chaos probe's velocity perturbation
    perturbation_seed: int = 0      # its seed (+ the specimen's index)
    mapping_json: str = '{"stress_mapping":"none"}'   # the stress mapping's record at the test
    stone_model: str = DEFAULT      # how the stones are modelled (ballaststudy.stones)
    splitting_json: str = "null"    # how rigid stones split (splitting_of; null: they do not)

    @property
    def rig(self):
        """The rig's parameters (a fresh params object)."""
        return params_class(self.kind)(**json.loads(self.rig_json))

    @property
    def covariates(self):
        return json.loads(self.covariates_json)

    @property
    def metrics(self):
        return json.loads(self.metrics_json)

    @property
    def splitting(self):
        """Simulation.enable_crushing's arguments but the seed (None: stones do not split)."""
        return json.loads(self.splitting_json)

    def splitting_for(self, seed):
        """The splitting of a specimen whose strengths are drawn from ``seed`` (None: off)."""
        return None if self.splitting is None else {**self.splitting, "seed": int(seed) % 2 ** 53}

    @property
    def mapping(self):
        """The stress mapping's record at this scenario's test (StressMapping.record)."""
        return json.loads(self.mapping_json)

    def modifier_values(self):
        """[(name, {parameter: value})] in the order they are applied."""
        return [(name, dict(values)) for name, values in self.modifiers]

    def material_values(self):
        """{name: value} of its material modifiers (Table 4.2's parameters it changes)."""
        return {k: v for name, values in self.modifiers if MODIFIERS[name].role == "material"
                for k, v in values}

    def deciding_rig(self):
        """{parameter: value} of the rig as the run sees it (the modifiers' rig settings
        applied), its inert parameters left out."""
        params = self.rig
        for name, _ in self.modifiers:
            MODIFIERS[name].set_rig(params)
        return {k: v for k, v in params.to_dict().items() if k not in params.inert_keys()}

    def read_covariates(self):
        """The declared covariates its modifiers read (the others act on nothing)."""
        read = {MODIFIERS[name].covariate for name, _ in self.modifiers}
        return {k: v for k, v in self.covariates.items() if k in read}

    @property
    def key(self):
        return self._hash(self.deciding_rig())

    @property
    def first_cycle_key(self):
        """The key of its cycle 0: what cycle 0 does not read left out of the rig too
        (``first_cycle_inert_keys``: the test's f). Scenarios of one first_cycle_key have
        the same cycle 0 (runner.run_cases runs it once)."""
        rig = self.deciding_rig()
        return self._hash({k: v for k, v in rig.items() if k not in self.rig.first_cycle_inert_keys()})

    def _hash(self, rig):
        probe = ({"perturbation_m_s": self.perturbation_m_s, "perturbation_seed": self.perturbation_seed}
                 if self.perturbation_m_s else {})
        mapped = key_of(self.mapping)
        probe.update({"stress_mapping": mapped} if mapped else {})
        # the thesis' bonded stones keep the keys they had before the switch existed
        probe.update({"stone_model": self.stone_model} if self.stone_model != DEFAULT else {})
        probe.update({"splitting": self.splitting} if self.splitting is not None else {})
        text = _canonical({"kind": self.kind, "specimens": list(self.specimen_hashes),
                           "rig": rig, "cycles": self.cycles,
                           "modifiers": [[n, _rounded(dict(v))] for n, v in self.modifiers],
                           "covariates": self.read_covariates(), "metrics": self.metrics, **probe})
        return hashlib.sha1(text.encode()).hexdigest()[:12]


STONE_MODEL_STAGES = ("calibration.parameters", "loop.effects", "parametric")


def _named_modifiers(cfg, key):
    """The modifier names a stage's config names: a list or the keys of a mapping under
    ``key`` ("calibration.parameters", "loop.effects"), or the one-at-a-time keys of a
    section given values ("parametric")."""
    node = cfg
    for part in key.split("."):
        node = (node or {}).get(part) or {}
    if key == "parametric":
        return [k for k, v in node.items() if k in MODIFIERS and v]
    return list(node)


def splitting_of(cfg):
    """Simulation.enable_crushing's arguments but the seed from the config's
    ``rigid_stones`` section (None unless its splitting is on)."""
    rs = cfg.get("rigid_stones") or {}
    if not rs.get("splitting"):
        return None
    return dict(criterion=rs["criterion"], sigma0=[float(v) for v in rs["strength_sigma0_Pa"]],
                m=[float(v) for v in rs["weibull_modulus"]],
                d0=float(rs["reference_diameter_m"]), fines_diameter=float(rs["fines_diameter_m"]),
                every=int(rs["check_every_steps"]))


def check_stone_model(cfg, file, backend=None, model=None, parameters=None,
                      stages=STONE_MODEL_STAGES):
    """What the stone model (``model``, default the config's) cannot run, refused in one
    line (ConfigError) before anything runs: splitting (rigid_stones.splitting) for a
    model whose stones do not split; a modifier the ``stages`` name (calibration
    parameters, loop effects) or a calibrated value (``parameters``: (file, {name:
    value})) acting on flat joints where the model has none, or on splitting stones where
    none split; the GPU batch (``backend``, default the config's) for a model it does not
    step. Returns the model's name."""
    model = stone_model_named(model or cfg.get("stone_model", DEFAULT))
    splits = splitting_of(cfg) is not None
    if splits and not model.can_split:
        raise ConfigError(file, "rigid_stones.splitting", f"true: stone_model {model.name}'s stones "
                          "do not split; allowed: stone_model rigid, or splitting false")
    named = [(file, key if key != "parametric" else f"{key}.{m}", m) for key in stages
             for m in _named_modifiers(cfg, key)]
    if parameters is not None:
        named += [(parameters[0], "parameters", m) for m in parameters[1]]
    for where, key, m in named:
        if m in MODIFIERS and MODIFIERS[m].needs_flat_joints and not model.has_flat_joints:
            raise ConfigError(where, key, f"{m} acts on flat joints, which stone_model "
                              f"{model.name} has not; allowed: stone_model bonded, or leave {m} out")
        if m in MODIFIERS and MODIFIERS[m].needs_splitting and not splits:
            raise ConfigError(where, key, f"{m} acts on the strengths of splitting stones; allowed: "
                              f"stone_model rigid with rigid_stones.splitting true, or leave {m} out")
    if not model.gpu_batch and (backend or cfg.get("backend", "cpu")) == "cuda":
        raise ConfigError(file, "backend", f"cuda: the GPU batch runs bonded stones only; allowed: "
                          f"backend cpu with stone_model {model.name}")
    return model.name


def conditioned_rig(kind, rig_config, conditions=None, mode=None, conditions_file="conditions",
                    mapping=None):
    """(params, mapping record): the kind's parameters from the config's ``rig`` section with
    a measured test's conditions (``measured.importer.load_conditions`` of
    ``conditions_file``), the stress ``mapping`` (mapping.StressMapping; None: none) of the
    test's q bounds onto the biaxial specimen, and a biaxial loading mode applied.
    ConfigError naming the conditions file if the test is not one the kind runs or its
    bounds clash with the config's."""
    params = params_from_config(kind, rig_config or {})
    mapping = mapping or StressMapping()
    record = {"stress_mapping": "none"}
    if conditions is not None:
        if conditions["rig"] not in RUNS_TESTS[kind]:
            raise ConfigError(conditions_file, "rig", f"{conditions['rig']}: a {kind} case runs "
                              f"{' or '.join(RUNS_TESTS[kind])} conditions")
        try:
            params.take_conditions(conditions)
        except ValueError as err:     # a bound of the test against the config's other bound
            raise ConfigError(conditions_file, None, str(err)) from None
        record = mapping.apply(params)      # a box stage's is none (mapping.stage_mapping)
    if mode:
        params.mode = mode      # biaxial only: the caller checks
    return params, record


def _shifted(value):
    if isinstance(value, bool) or not isinstance(value, (int, float, list)):
        return value
    if isinstance(value, list):
        return [_shifted(v) for v in value]
    return type(value)(value * 1.37 + 1)


def conditioned_keys(kind, conditions_list):
    """The rig parameters every test of ``conditions_list`` sets whatever the config says
    (take_conditions): a stage run under these tests ignores the config's values, so they
    are no rerun trigger of it. Found by applying each test's conditions to the defaults
    and to every number shifted: a key that ends equal was set by the test (a key scaled by
    it, like the box rig's preloads, still depends on the config and stays)."""
    cls = params_class(kind)
    base = cls().to_dict()
    kept = set(base)
    for c in conditions_list:
        a, b = cls(**base), cls(**{k: _shifted(v) for k, v in base.items()})
        try:
            a.take_conditions(c)
            b.take_conditions(c)
        except ValueError:          # a shifted bound against the test's: decide nothing
            return ()
        da, db = a.to_dict(), b.to_dict()
        kept &= {k for k in base if da[k] == db[k] and base[k] != _shifted(base[k])}
    return tuple(sorted(kept)) if conditions_list else ()


def scenario(kind, specimens, rig, cycles, modifiers=(), conditions=None, conditions_file="",
             metrics=None, perturbation_m_s=0.0, perturbation_seed=0, mapping=None, stone_model=DEFAULT,
             splitting=None):
    """A Scenario from plain values: ``rig`` a params object and ``mapping`` its stress
    mapping's record (both from conditioned_rig; None: none), ``modifiers`` [(name,
    {parameter: value})] checked against the registry and the stone model (``stone_model``:
    ballaststudy.stones; ``splitting``: splitting_of's, None: its stones do not split),
    ``conditions`` the loaded test (its covariates are kept)."""
    model = stone_model_named(stone_model)
    if splitting is not None and not model.can_split:
        raise ValueError(f"the {model.name} stone model's stones do not split")
    for name, values in modifiers:
        MODIFIERS[name].check(values)
        if MODIFIERS[name].needs_flat_joints and not model.has_flat_joints:
            raise ValueError(f"modifier {name} acts on flat joints; the {model.name} stone model has none")
        if MODIFIERS[name].needs_splitting and splitting is None:
            raise ValueError(f"modifier {name} acts on splitting stones; these do not split")
    specimens = tuple(str(s) for s in specimens)
    return Scenario(
        kind=kind, specimens=specimens, specimen_hashes=tuple(content_hash(s) for s in specimens),
        rig_json=_canonical(rig.to_dict()), cycles=int(cycles),
        modifiers=tuple((name, tuple(sorted((k, float(v)) for k, v in values.items())))
                        for name, values in modifiers),
        covariates_json=_canonical((conditions or {}).get("covariates") or {}),
        metrics_json=_canonical(metrics), conditions_file=str(conditions_file or ""),
        perturbation_m_s=float(perturbation_m_s), perturbation_seed=int(perturbation_seed),
        mapping_json=_canonical(mapping or {"stress_mapping": "none"}), stone_model=model.name,
        splitting_json=_canonical(splitting))
