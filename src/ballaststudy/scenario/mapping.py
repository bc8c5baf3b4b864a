"""The declared stress mapping between a measured 3D triaxial test and the 2D biaxial
specimen that stands for it (config section ``stress_mapping``). It is a modelling
assumption, so its default is ``none`` and every output it affects names it.

- ``none``: the 2D specimen carries the lab test's p and q bounds as they are.
- ``strength_ratio``: at the test's p the 2D specimen is loaded to the same fraction of its
  own peak deviator as the lab test loads the real ballast to its peak,

      q_2D = q_lab * r(p),   r(p) = q_peak_2D(p) / q_peak_lab(p),

  both bounds (q_min and q_max) scaled by the same r, p kept. Why: a 2D disk assembly is
  weaker than the stones it stands for (phi_peak ~ 42-50 deg against >= 67 at low p in the
  lab, issue 32), so the lab's q puts it at or beyond failure where the lab specimen shakes
  down; equal mobilised strength keeps the specimen on the same side of failure as the test.

  q_peak_2D(p): the specimen set's strength envelope (``snakemake strength``, rule
  ``strength_envelope``), its mean over the cases at p. It is measured once, at the config's
  material (Table 4.2's), and held fixed for every parameter set a calibration or the loop
  tries: the mapping is a statement about the loads, which must be the same for all the sets
  compared. q_peak_lab(p): the config's cited lab envelope (``lab_envelope``: large triaxial
  tests on the material), interpolated log-log between its points (a power law q ~ p^b
  between neighbours, the shape of ballast's curved peak envelopes; exact at the points),
  never extrapolated.
"""
from dataclasses import dataclass

import numpy as np

from ..config import check_stress_mapping
from ..inputs import open_netcdf
from ..rig.biaxial.params import KPA
from ..schema import ConfigError

SECTION = "stress_mapping"


@dataclass(frozen=True)
class StressMapping:
    kind: str = "none"
    config_file: str = ""              # where the mapping was declared (errors name it)
    citation: str = ""
    lab_p_kPa: tuple = ()
    lab_q_peak_kPa: tuple = ()
    envelope_file: str = ""            # the 2D specimens' strength envelope
    model_p_kPa: tuple = ()
    model_q_peak_kPa: tuple = ()       # its mean over the cases at each p
    model_peak_share: tuple = ()       # share of those cases whose q fell past its peak

    @property
    def applied(self):
        return self.kind != "none"

    def lab_q_peak_kPa_at(self, p_kPa):
        """The lab's peak deviator at p [kPa], log-log between the envelope's points."""
        p, q = np.asarray(self.lab_p_kPa, float), np.asarray(self.lab_q_peak_kPa, float)
        if not p[0] * (1 - 1e-9) <= p_kPa <= p[-1] * (1 + 1e-9):
            raise ConfigError(self.config_file, f"{SECTION}.lab_envelope.confining_pressure_kPa",
                              f"p = {p_kPa:g} kPa lies outside the envelope's {p[0]:g}-{p[-1]:g} "
                              "kPa (it is not extrapolated): add a point that covers it")
        if p.size == 1:
            return float(q[0])
        return float(np.exp(np.interp(np.log(p_kPa), np.log(p), np.log(q))))

    def _model_index(self, p_kPa):
        p = np.asarray(self.model_p_kPa, float)
        hit = np.flatnonzero(np.isclose(p, p_kPa, rtol=1e-9, atol=0.0))
        if hit.size == 0:
            raise ConfigError(self.envelope_file, "confining_pressure",
                              f"no strength test at p = {p_kPa:g} kPa (it has "
                              f"{', '.join(f'{v:g}' for v in p)} kPa); `snakemake strength` "
                              "tests every measured test's p")
        return int(hit[0])

    def model_q_peak_kPa_at(self, p_kPa):
        return float(self.model_q_peak_kPa[self._model_index(p_kPa)])

    def ratio(self, p_kPa):
        """r(p) = q_peak_2D(p) / q_peak_lab(p); 1 for ``none``."""
        if not self.applied:
            return 1.0
        return self.model_q_peak_kPa_at(p_kPa) / self.lab_q_peak_kPa_at(p_kPa)

    def apply(self, params):
        """Scale a biaxial params object's q bounds (a test's conditions already taken) by
        r at its p. Returns the record of what was done (``record``)."""
        if not self.applied:        # whatever the rig: nothing to read or scale
            return {"stress_mapping": "none"}
        rec = self.record(params.confining_pressure_kPa, params.deviator_min_kPa, params.deviator_max_kPa)
        params.deviator_min_kPa = rec["stress_mapping_deviator_min_kPa"]
        params.deviator_max_kPa = rec["stress_mapping_deviator_max_kPa"]
        return rec

    def record(self, p_kPa, q_min_kPa, q_max_kPa):
        """The mapping at one test as flat attributes (what outputs carry): its kind, and
        for strength_ratio r, both peaks, the lab's and the mapped bounds, the sources."""
        rec = {"stress_mapping": self.kind}
        if not self.applied:
            return rec
        k, r = self._model_index(p_kPa), self.ratio(p_kPa)
        rec.update({
            "stress_mapping_ratio": r,
            "stress_mapping_confining_pressure_kPa": float(p_kPa),
            "stress_mapping_lab_q_peak_kPa": self.lab_q_peak_kPa_at(p_kPa),
            "stress_mapping_model_q_peak_kPa": float(self.model_q_peak_kPa[k]),
            "stress_mapping_model_peak_share": float(self.model_peak_share[k]),
            "stress_mapping_lab_deviator_min_kPa": float(q_min_kPa),
            "stress_mapping_lab_deviator_max_kPa": float(q_max_kPa),
            "stress_mapping_deviator_min_kPa": float(q_min_kPa) * r,
            "stress_mapping_deviator_max_kPa": float(q_max_kPa) * r,
            "stress_mapping_lab_envelope_citation": self.citation,
            "stress_mapping_model_envelope_file": self.envelope_file})
        return rec


def key_of(record):
    """What of a mapping record decides a scenario's cases (its kind and r; the rest are
    labels or follow from the rig's bounds): {} for none."""
    if record.get("stress_mapping", "none") == "none":
        return {}
    return {"kind": record["stress_mapping"], "ratio": float(f"{record['stress_mapping_ratio']:.12g}")}


def read_model_envelope(path):
    """(p [kPa], mean q_peak [kPa], share of cases past their peak) per p of a strength
    envelope (rig.biaxial.strength.strength_envelope's file)."""
    ds = open_netcdf(path, "envelope")
    q = ds["q_peak_mean"].values / KPA
    if not np.all(np.isfinite(q)) or np.any(q <= 0):
        raise ConfigError(path, "q_peak_mean", f"{q} kPa: every p needs a positive peak")
    share = np.nanmean(ds["peak_reached"].values, axis=1)
    return tuple(ds["confining_pressure"].values / KPA), tuple(q), tuple(share)


def mapping_from_config(cfg, config_file, envelope_file=None):
    """The config's StressMapping (``envelope_file``: the 2D specimens' strength envelope,
    needed by strength_ratio and refused by none, where it would change nothing)."""
    sec = check_stress_mapping(cfg, config_file)
    if sec["kind"] == "none":
        if envelope_file:
            raise ConfigError("command line", "--strength-envelope", f"given, but {SECTION}.kind "
                              f"is none in {config_file}: it would change nothing")
        return StressMapping(config_file=str(config_file))
    if not envelope_file:
        raise ConfigError("command line", "--strength-envelope", f"missing: {SECTION}.kind "
                          f"{sec['kind']} in {config_file} needs the specimens' strength envelope "
                          "(snakemake strength_envelope: results/strength/<set>/envelope.nc)")
    env = sec["lab_envelope"]
    model_p, model_q, share = read_model_envelope(envelope_file)
    return StressMapping(kind=sec["kind"], config_file=str(config_file), citation=env["citation"].strip(),
                         lab_p_kPa=tuple(map(float, env["confining_pressure_kPa"])),
                         lab_q_peak_kPa=tuple(map(float, env["peak_deviator_kPa"])),
                         envelope_file=str(envelope_file), model_p_kPa=model_p, model_q_peak_kPa=model_q,
                         model_peak_share=share)


def stage_mapping(cfg, config_file, envelope_file, kind):
    """The StressMapping of a stage running ``kind`` specimens under measured tests: the
    config's for biaxial ones; none for box ones (a box test is loaded as measured), where an
    envelope given is refused."""
    if kind == "biaxial":
        return mapping_from_config(cfg, config_file, envelope_file)
    if envelope_file:
        raise ConfigError("command line", "--strength-envelope", f"maps a measured test's q onto "
                          f"biaxial specimens; these are {kind} specimens")
    return StressMapping(config_file=str(config_file))


def mapping_kinds(records):
    """The kind(s) of stress mapping a stage's tests ran under ({test: record}), as one word
    ("none" when there are none)."""
    return ", ".join(sorted({r["stress_mapping"] for r in records.values()})) or "none"


def mapping_markdown(records):
    """A report's lines on the stress mapping its tests ran under: ``records`` {test: record}
    (StressMapping.record)."""
    kinds = mapping_kinds(records)
    if kinds == "none":
        return ("Stress mapping: **none** (the 2D specimens carry the lab tests' p and q as they "
                "are; config `stress_mapping`).\n")
    rows = "\n".join(
        f"| {t} | {r['stress_mapping_confining_pressure_kPa']:g} | {r['stress_mapping_lab_q_peak_kPa']:.4g} | "
        f"{r['stress_mapping_model_q_peak_kPa']:.4g} ({100 * r['stress_mapping_model_peak_share']:.0f} %) | "
        f"{r['stress_mapping_ratio']:.4f} | "
        f"{r['stress_mapping_lab_deviator_min_kPa']:.4g}-{r['stress_mapping_lab_deviator_max_kPa']:.4g} | "
        f"{r['stress_mapping_deviator_min_kPa']:.4g}-{r['stress_mapping_deviator_max_kPa']:.4g} |"
        for t, r in records.items() if r["stress_mapping"] != "none")
    first = next(r for r in records.values() if r["stress_mapping"] != "none")
    return f"""Stress mapping: **{kinds}** (config `stress_mapping`, a modelling assumption):
each test's q bounds scaled by r = q_peak_2D(p) / q_peak_lab(p), so that the 2D specimens are
loaded to the fraction of their own peak at which the lab test loads the ballast. 2D envelope:
{first['stress_mapping_model_envelope_file']}; lab envelope: {first['stress_mapping_lab_envelope_citation']}.

2D q_peak is the mean over the set's strength tests at p; in brackets the share of them whose
q fell past its peak (the others were still rising at the test's end: their q_peak is a lower
bound, and so is r).

| test | p [kPa] | lab q_peak [kPa] | 2D q_peak [kPa] (past peak) | r | lab q [kPa] | 2D q run [kPa] |
|---|---|---|---|---|---|---|
{rows}
"""
