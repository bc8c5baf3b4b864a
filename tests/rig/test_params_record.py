"""Params read back from a file of ours (an assembled case, a checkpoint): a key a later
version retired is dropped, a key it added takes its default; the rest as recorded."""
from ballaststudy.rig.biaxial import BiaxialParams
from ballaststudy.rig.params import RigParams


def test_retired_keys_dropped_new_keys_defaulted():
    for cls in (BiaxialParams, RigParams):
        recorded = cls(relax_steps=1234).to_dict()
        recorded["a_retired_key_m_s"] = 0.005
        new_key = "rolling_friction"
        del recorded[new_key]
        p = cls.from_record(recorded)
        assert p.relax_steps == 1234
        assert getattr(p, new_key) == getattr(cls(), new_key)
        assert not hasattr(p, "a_retired_key_m_s")
