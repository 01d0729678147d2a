"""Shared, seeded fixtures.

``model_dataset``: 2 h (1440 samples at Ts = 5 s) of the paper-preset model plant excited
with the default APRBS (``ExcitationSpec()``, seed 0), T_int/T_shell varied, no noise;
temperatures in degC, so the true parameters are ``acid.params.paper()``.
``noisy_model_dataset``: the same run with 0.05 K measurement noise on T_cab, T_evap, T_ain.
Both are session-scoped (built once, ~20 ms each): treat them as read-only (use
``ds.window(...)`` or copies before modifying).
``exported_fmu``: ``acid export-fmu`` of the default high-fidelity plant (FMI 2.0) and its
map, built once per session (~0.1 s).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from acid.excite import ExcitationSpec, excite
from acid.plant import make_plant

# Property-based tests: modest in the suite, thorough on demand
# (pytest --hypothesis-profile=acid-thorough tests/test_readers_property.py).
_PROFILE = {"deadline": None, "database": None, "derandomize": False,
            "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.filter_too_much]}
settings.register_profile("acid-ci", max_examples=150, **_PROFILE)
settings.register_profile("acid-thorough", max_examples=1500, **_PROFILE)
settings.load_profile("acid-ci")


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh generator seeded with 0 for each test."""
    return np.random.default_rng(0)


@pytest.fixture(scope="session")
def model_spec() -> ExcitationSpec:
    """The excitation behind ``model_dataset`` (defaults: 7200 s APRBS, seed 0)."""
    return ExcitationSpec(seed=0)


@pytest.fixture(scope="session")
def model_dataset(model_spec):
    """2 h of noise-free paper-preset model-plant data with varied T_int/T_shell."""
    plant = make_plant("model", rng=model_spec.rng("noise"))
    return excite(plant, model_spec)


@pytest.fixture(scope="session")
def noisy_model_dataset(model_spec):
    """As ``model_dataset`` with 0.05 K white measurement noise on the temperatures."""
    spec = model_spec.replace(noise=0.05)
    plant = make_plant("model", meas_noise_std=spec.noise, rng=spec.rng("noise"))
    return excite(plant, spec)


@pytest.fixture(scope="session")
def exported_fmu(tmp_path_factory):
    """acid's high-fidelity plant exported once per session as an FMI 2.0 FMU, with its map:
    ``(fmu_path, map_path)``."""
    from acid.plant.fmu_export import export_fmu

    folder = tmp_path_factory.mktemp("fmu")
    result = export_fmu(folder / "plant.fmu", map_out=folder / "plant.toml")
    return result.fmu, result.fmu_map
