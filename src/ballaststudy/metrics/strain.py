"""Strains of a biaxial (2D cyclic triaxial) specimen since a reference state (the end of
consolidation), compression positive: axial 1 - H/H0, volumetric (2D: area) 1 - W H / (W0 H0),
H between the platens and W the mean width between the sides (area / height)."""


def axial_strain(height, height0):
    """Axial strain of a specimen now ``height`` [m] that was ``height0`` [m]."""
    return 1.0 - height / height0


def specimen_strains(height, width, height0, width0):
    """(axial, volumetric) strain of a specimen now ``height`` x ``width`` [m] that was
    ``height0`` x ``width0`` [m] at the reference state."""
    return axial_strain(height, height0), 1.0 - (width * height) / (width0 * height0)
