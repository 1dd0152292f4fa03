"""Camera parameters of :mod:`flexsat.identify.photogrammetry` that must be one number are
refused by name when given as arrays, strings or non-finite values (they ended in a numpy
``TypeError`` from ``float()``)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify.photogrammetry import Camera, simulate_centroids
from flexsat.input_checks import FieldError

NAN = np.nan
NOT_ONE_NUMBER = [NAN, np.inf, [], "abc", np.ones(2), np.ones((2, 2))]


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field == field, str(err.value)


@pytest.mark.parametrize("bad", NOT_ONE_NUMBER, ids=repr)
@pytest.mark.parametrize("field", ["f", "fx", "x0", "y0", "k1", "k2", "p1", "p2"])
def test_camera_scalars_refused_by_name(field, bad):
    given = {"position": [0.0, 0.0, 10.0], "angles": [0.0, 0.0, 0.0], "f": 1.0, field: bad}
    if field == "fx":
        given.update(f=None, fy=1.0)
    _raises(field, lambda: Camera(**given))


@pytest.mark.parametrize("bad", NOT_ONE_NUMBER, ids=repr)
def test_centroid_noise_refused_by_name(bad):
    camera = Camera([0.0, 0.0, 10.0], [0.0, 0.0, 0.0], f=1.0)
    _raises("noise_px", lambda: simulate_centroids([camera], np.zeros((1, 3)), 1e-5, bad))
