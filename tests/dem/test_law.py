"""Contact laws as compositions of registered sub-models (law.py, submodels.py)."""
import pytest

from ballaststudy.dem import ContactMaterial, Simulation
from ballaststudy.dem import submodels as K
from ballaststudy.dem.law import ContactLaw


@pytest.mark.parametrize("law", [ContactLaw.pfc(), ContactLaw.hooke(), ContactLaw.pfc("epsd"),
                                 ContactLaw.hooke("epsd")])
def test_packed_layout_matches_the_registry(law):
    key = law.layout()
    field = lambda f: int(K.lf(key, f))                     # noqa: E731
    assert [field(k) for k in range(4)] == [sm.code for sm in law.parts]
    starts, c = [], 0
    for sm in law.parts:
        starts.append(c)
        c += len(sm.coefficients)
    assert [field(K.C_DAMPING), field(K.C_TANGENTIAL), field(K.C_ROLLING)] == starts[1:]
    assert field(K.H_TANGENTIAL) == law.history_column("tangential")
    assert field(K.H_ROLLING) == law.history_column("rolling")
    assert field(K.WIDTH) == law.history_width
    assert law.width == law.history_width + len(law.state_names)
    assert law.coefficients[law.column("mu")] == "mu"


def test_bad_compositions_and_coefficients_are_refused():
    with pytest.raises(ValueError, match="known"):
        ContactLaw(rolling="sticky")
    with pytest.raises(ValueError, match="needs coefficients"):
        Simulation(law="hooke")                                    # no hooke=dict(...)
    sim = Simulation(law=ContactLaw.pfc("epsd"))
    with pytest.raises(KeyError):
        sim.set_contact_coefficient("kn", 1.0)                     # not a column of this law
    sim.set_contact_material(ContactMaterial(mu_r=0.3), 0, 1)
    assert sim.contact_coefficient("mu_r")[0, 1] == sim.contact_coefficient("mu_r")[1, 0] == 0.3
    assert sim.contact_coefficient("mu_r")[0, 0] == 0.0
