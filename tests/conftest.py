"""Shared, seeded fixtures.

``model_dataset``: 2 h (1440 samples at Ts = 5 s) of the paper-preset model plant excited
with the default APRBS (``ExcitationSpec()``, seed 0), T_int/T_shell varied, no noise;
temperatures in degC, so the true parameters are ``acid.models.params.paper()``.
``noisy_model_dataset``: the same run with 0.05 K measurement noise on T_cab, T_evap, T_ain.
Both are session-scoped (built once, ~20 ms each): treat them as read-only (use
``ds.window(...)`` or copies before modifying).
``exported_fmu``: ``acid export-fmu`` of the default high-fidelity plant (FMI 2.0) and its
map, built once per session (~0.1 s).
"""

from __future__ import annotations

import os
import sys

# One BLAS thread per test process (set before numpy loads OpenBLAS; the CLI processes and
# Dask workers the tests start inherit it). Two xdist workers on two cores, each with an
# OpenBLAS pool spinning on every core, spend most of their CPU waiting on each other: at load
# 17, tests/test_validate.py took 116 CPU-s with the default pool and 11 CPU-s with one thread
# (the yardsticks' least squares). A user's own setting is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# Bytecode kept between the processes the suite starts: where PYTHONDONTWRITEBYTECODE is set
# (this machine sets it), every xdist worker and every `acid` subprocess compiled acid's
# modules again (about 0.2 CPU-s per command started, 4-5 CPU-s per worker). The compiled
# files go to __pycache__ beside the sources, as a plain install would put them.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402

from acid.excite import ExcitationSpec, excite  # noqa: E402
from acid.plant import make_plant  # noqa: E402
from acid.plant.declared import econ_plant  # noqa: E402

# Property-based tests: modest in the suite, thorough on demand
# (pytest --hypothesis-profile=acid-thorough tests/test_readers_property.py).
_PROFILE = {"deadline": None, "database": None, "derandomize": False,
            "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.filter_too_much]}
settings.register_profile("acid-ci", max_examples=150, **_PROFILE)
settings.register_profile("acid-thorough", max_examples=1500, **_PROFILE)
settings.load_profile("acid-ci")

# pytest-xdist starts its workers with COLUMNS=80: the CLI would then cut its tables at 80
# columns instead of the width it renders into a log (LOG_COLUMNS), unlike a plain pytest run.
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.pop("COLUMNS", None)


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
    from acid.plant.fmi.export import export_fmu

    folder = tmp_path_factory.mktemp("fmu")
    result = export_fmu(folder / "plant.fmu", map_out=folder / "plant.toml")
    return result.fmu, result.fmu_map


# ------------------------------------------------------------------ econ model family
ECON_TRUTH = {"r_max": 0.8, "k_rec": 0.1, "ntu_ref": 2.75, "ntu_exp": 0.4, "kappa_bl": 0.1,
              "C_cab": 4500.0, "hA_int": 190.0, "hA_sh": 67.0, "Q_cab": 80.0,
              "C_int": 65000.0, "Q_int": 350.0, "C_sh": 65000.0, "hA_ext0": 60.0,
              "hA_ext_v": 9.0, "Q_sh": 900.0, "tau_ew": 11.0, "dT_ew": 0.1, "M_cab": 3.7,
              "m_w": 1.4e-5, "RH_amb": 0.5}
#: an inverse-COP map of the size identified on the high-fidelity plant
ECON_MAP = (0.155, 0.051, -0.029, -0.006, 0.05, -0.004, -0.01, -0.0015, 0.0027, 0.0022,
            0.0005, -0.005, 0.0014, -0.0015, -0.0052)


@pytest.fixture(scope="session")
def econ_truth():
    """A known econ parameter set (sizes as identified on the high-fidelity plant)."""
    from acid.models.econ_params import EconParams, PowerMap

    domain = {"Q_e": (-500.0, 6000.0), "T_evap": (270.0, 290.0), "v_veh": (0.0, 35.0),
              "T_amb": (290.0, 320.0)}
    return EconParams(values=dict(ECON_TRUTH), C_ew=2000.0,
                      power_map=PowerMap(coef=ECON_MAP, domain=domain), name="truth")


@pytest.fixture(scope="session")
def econ_model_dataset(econ_truth):
    """2 h of the econ model as a plant, excited as ``acid excite --model econ`` (seed 1)."""
    from acid.excite import spec_for_model

    return excite(econ_plant(econ_truth.theta_all),
                  spec_for_model("econ", duration=2 * 3600.0, seed=1))


@pytest.fixture(scope="session")
def econ_hifi_dataset():
    """3 h of the high-fidelity plant excited as ``acid excite --model econ`` (seed 0)."""
    from acid.excite import spec_for_model

    return excite(make_plant("hifi"), spec_for_model("econ", duration=3 * 3600.0, seed=0))


@pytest.fixture(scope="session")
def econ_hifi_fit(econ_hifi_dataset):
    """The econ model identified on the first 3/4 of ``econ_hifi_dataset``."""
    import warnings

    from acid.ident.econ import identify

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(econ_hifi_dataset.split(0.75)[0])


# ------------------------------------------------------------------ scheduling
#: The files that take longest, longest first (seconds of one quiet full run on 2 cores, see
#: notes/suiteA.md). They are collected first so that, with ``--dist loadfile
#: --no-loadscope-reorder`` (pyproject.toml), the two workers start on them and the many short
#: files fill in behind: a long file handed out last would run alone at the end of the suite.
#: A file missing here is only scheduled later; renaming one costs time, never a test.
SLOWEST_FIRST = (
    "test_studies_reproduce.py",
    "test_signals_shutdown.py",
    "test_day_cli.py",
    "test_studies_day.py",
    "test_studies_cav_study.py",
    "test_studies_compare.py",
    "test_reliability_round4.py",
    "test_studies_sweep_econ.py",
    "test_docs.py",
    "test_studies_reproduce_interrupts.py",
    "test_degC_edges.py",
    "test_sweep_cli.py",
    "test_studies_heating_control.py",
    "test_compare_cli.py",
    "test_models_car_power.py",
    "test_processes_left.py",
    "test_cli_interrupts.py",
    "test_control_codegen_export.py",
    "test_import_gaps.py",
    "test_plant_check_cli.py",
    "test_plant_heating_excite.py",
    "test_validate_cli.py",
)


def pytest_collection_modifyitems(config, items):
    """Order the collected tests by ``SLOWEST_FIRST`` (stable: the rest keep their order)."""
    rank = {name: i for i, name in enumerate(SLOWEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
