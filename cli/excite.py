"""``acid excite``: random excitation of a plant into an HDF5 identification dataset."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import typer

from acid.data import Dataset
from acid.errors import ConfigError
from acid.excite import DESIGNS, MODEL_PRESETS, SIGNAL_TYPES, ExcitationSpec, spec_for_model
from acid.excite import excite as run_excitation
from acid.plant.vehicles import vehicle_label
from acid.units import C2K
from acid_cli._common import (
    check_paths,
    handle_errors,
    plant_inputs,
    print_table,
    progress_bar,
    require,
    require_range,
    say,
    write_summary,
)
from acid_cli._plant import (
    config_input,
    fmu_map_option,
    identity_line,
    plant_choice,
    plant_identity,
    plant_overrides,
    recorded_identity,
    refrigerant_option,
)

PLANTS = ("hifi", "model")
#: ``--plant model:FILE.py`` (or ``model:NAME``, a built-in declaration): a declared model.
DECLARED_PREFIX = "model:"

#: Ambient temperatures accepted here, degC: a kelvin value typed by mistake is refused; the
#: plant refuses what its own tables do not cover.
T_AMB_RANGE_C = (-60.0, 150.0)


def build_plant(name: str, spec: ExcitationSpec, params: Path | None,
                plant_config: Path | None, T_amb: float | None,
                fmu_map: Path | None = None, allow_unstable: bool = False,
                refrigerant: str | None = None):
    """The plant chosen by ``--plant``, with the spec's noise and the noise stream's seed.

    A plant that is not available in this installation (``--plant hifi`` before the
    high-fidelity modules exist, or without their dependencies) is a one-line ``ConfigError``.
    """
    if refrigerant is not None and name != "hifi":
        raise ConfigError(f"--refrigerant applies to --plant hifi only, not {name!r}")
    if name.startswith(DECLARED_PREFIX):
        return declared_plant(name[len(DECLARED_PREFIX):], spec, params, plant_config, T_amb,
                              fmu_map)
    if T_amb is not None and name in ("heating", "hifi"):
        plant_overrides(t_amb=T_amb)   # within the plant's property tables, naming --t-amb
    if name == "heating":  # the heating plant as the logged i3 (acid.plant.heating_excite)
        from acid.plant.heating_config import winter_plant_config
        from acid.plant.heating_excite import HeatingExcitation

        for flag, given in (("--params", params), ("--plant-config", plant_config),
                            ("--fmu-map", fmu_map)):
            if given is not None:
                raise ConfigError(f"{flag} does not apply to --plant heating")
        return HeatingExcitation(config=winter_plant_config(
            None if T_amb is None else C2K(T_amb)))
    choice = plant_choice(name, fmu_map, allowed=PLANTS)
    if choice.kind != "model" and params is not None:
        raise ConfigError("--params applies to --plant model only (the high-fidelity plant "
                          "is configured with --plant-config)")
    if choice.kind != "hifi" and plant_config is not None:
        raise ConfigError("--plant-config applies to --plant hifi only (the model plant "
                          "takes --params, an FMU plant --fmu-map)")
    if plant_config is not None and not Path(plant_config).is_file():
        raise ConfigError(f"--plant-config: file not found: {plant_config}")
    model_params = None
    if choice.kind == "model":
        from acid.models.params import load_params

        model_params = load_params(params, allow_unstable=allow_unstable)
    extra = {} if refrigerant is None else plant_overrides(refrigerant=refrigerant)
    try:
        return choice.make(config_path=plant_config, params=model_params,
                           meas_noise_std=spec.noise, rng=spec.rng("noise"),
                           T_amb=None if T_amb is None else C2K(T_amb), **extra)
    except ImportError as exc:
        raise ConfigError(f"--plant {name}: not available in this installation ({exc}); "
                          f"use --plant model") from None


def declared_plant(model_spec: str, spec: ExcitationSpec, params: Path | None,
                   plant_config: Path | None, T_amb: float | None, fmu_map: Path | None):
    """``--plant model:FILE.py``: the declared model as a plant (``DeclaredPlant``), with the
    values of ``--params`` (a parameter file of ``acid fit --model``) or its declared ones."""
    from acid.ident.validate import read_parameters
    from acid.models import load
    from acid.plant.declared import DeclaredPlant

    for flag, given in (("--plant-config", plant_config), ("--fmu-map", fmu_map),
                        ("--noise", spec.noise != 0.0)):
        if given:
            raise ConfigError(f"{flag} does not apply to --plant {DECLARED_PREFIX}"
                              f"{model_spec} (a declared model)")
    if not model_spec:
        raise ConfigError(f"--plant {DECLARED_PREFIX}FILE.py: the model file is missing")
    model = load(model_spec)
    values = None if params is None else read_parameters(model, params).theta
    return DeclaredPlant(model, values, **({} if T_amb is None else {"T_amb": C2K(T_amb)}))


def _summary_rows(ds: Dataset) -> list[list[str]]:
    rows = []
    for name, values in ds.channels.items():
        rows.append([name, ds.units[name], f"{values.min():.3g}", f"{values.mean():.3g}",
                     f"{values.max():.3g}"])
    return rows


@handle_errors
def excite(
    out: Path = typer.Option(..., "--out", "-o", help="HDF5 dataset to write (atomically)."),
    plant: str = typer.Option(
        "hifi", "--plant",
        help="Plant: 'hifi' (high-fidelity), 'model' (paper eqs. 1-5), 'heating' (the "
             "heating plant as the logged i3: random heater power, fixed blower; for "
             "acid fit --model heating), 'model:FILE.py' (a "
             "declared model, or model:paper|econ|cabin3; its inputs and disturbances "
             "driven by the schedule, --params a parameter file of acid fit --model) or "
             "'fmu:PATH.fmu' (your FMI 2.0/3.0 co-simulation FMU, with --fmu-map)."),
    fmu_map: Path | None = fmu_map_option(),
    duration: float | None = typer.Option(
        None, "--duration", help="Record length, s (default 7200, 21600 for --model econ)."),
    signal: str = typer.Option("aprbs", "--signal",
                               help=f"Input signal: {', '.join(SIGNAL_TYPES)}."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random stream."),
    speed: float = typer.Option(0.0, "--speed", help="Constant vehicle speed, m/s."),
    cycle: str | None = typer.Option(None, "--cycle",
                                     help="Drive cycle from datasets/drive_cycles (e.g. "
                                          "udds), repeated to fill the record."),
    min_dwell: float = typer.Option(20.0, "--min-dwell", help="APRBS minimum dwell, s."),
    max_dwell: float = typer.Option(300.0, "--max-dwell", help="APRBS maximum dwell, s."),
    noise: float = typer.Option(0.0, "--noise",
                                help="Measurement noise std on recorded temperatures, K."),
    params: Path | None = typer.Option(None, "--params",
                                       help="params.json for --plant model (default: the "
                                            "paper's values)."),
    vary_exogenous: bool = typer.Option(True, "--vary-exogenous/--no-vary-exogenous",
                                        help="Vary T_int/T_shell (model plant only)."),
    plant_config: Path | None = typer.Option(None, "--plant-config",
                                             help="TOML configuration of --plant hifi."),
    t_amb: float | None = typer.Option(None, "--t-amb",
                                       help="Ambient temperature, degC (default: the "
                                            "plant's, 30 degC in Table II)."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Use --params even if eqs. 1-3 are unstable or not in kelvin."),
    json_out: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    model: str = typer.Option(
        "paper", "--model",
        help="What the record is for: 'paper' (eqs. 1-5: one speed and ambient) or 'econ' "
             "(`acid fit --model econ`: random speed 0-36 m/s, ambient 25-40 degC, steady "
             "holds, 6 h)."),
    speed_range: tuple[float, float] | None = typer.Option(
        None, "--speed-range", help="Random vehicle speed between LOW HIGH m/s (APRBS)."),
    refrigerant: str | None = refrigerant_option(),
    t_amb_range: tuple[float, float] | None = typer.Option(
        None, "--t-amb-range", help="Slowly varying ambient between LOW HIGH degC."),
    steady_fraction: float | None = typer.Option(
        None, "--steady-fraction",
        help="Share of input steps held 600-1200 s (near-steady operating points)."),
    design: str = typer.Option(
        "random", "--design",
        help="Record design: 'random' (one experiment from the plant's soak) or 'pulldown' "
             "(separate experiments, each from a hot soak in --soak-range or a cold soak at "
             "the ambient, pulled down at full power, then random inputs)."),
    soak_range: tuple[float, float] | None = typer.Option(
        None, "--soak-range", help="Hot soak temperatures LOW HIGH, degC (--design pulldown; "
                                   "default 30 55)."),
    segment_duration: float | None = typer.Option(
        None, "--segment-duration", help="Length of each pull-down, s (--design pulldown; "
                                         "default 1800)."),
) -> None:
    """Excite a plant with random inputs within Table II bounds and record a dataset at 0.2 Hz."""
    plant_config_given = plant_config
    plant_config = config_input(plant_config)  # a named vehicle ('paper') -> its file
    model_file = plant[len(DECLARED_PREFIX):] if plant.startswith(DECLARED_PREFIX) else ""
    check_paths(inputs={"--params": params, "--plant-config": plant_config,
                        **plant_inputs(plant, fmu_map),
                        **({"--plant": model_file} if model_file.endswith(".py") else {})},
                outputs={"--out": out, "--json": json_out})
    if t_amb is not None:
        require_range(t_amb, "--t-amb", *T_AMB_RANGE_C, "degC")
    if cycle is not None and speed != 0.0:
        raise ConfigError("--speed and --cycle are exclusive (give one speed profile)")
    if model not in MODEL_PRESETS:
        raise ConfigError(f"--model: unknown model family {model!r} (choose "
                          f"{', '.join(MODEL_PRESETS)})")
    if design not in DESIGNS:
        raise ConfigError(f"--design: unknown design {design!r} (choose {', '.join(DESIGNS)})")
    if design != "pulldown" and (soak_range is not None or segment_duration is not None):
        raise ConfigError("--soak-range and --segment-duration apply to --design pulldown only")
    for opt, rng_ in (("--speed-range", speed_range), ("--t-amb-range", t_amb_range),
                      ("--soak-range", soak_range)):
        if rng_ is not None:
            lo_, hi_ = rng_
            require(all(isinstance(x, (int, float)) and math.isfinite(x) for x in rng_)
                    and lo_ < hi_, opt, f"needs LOW < HIGH, both finite, got {lo_:g} {hi_:g}")
    given = {"speed_bounds": speed_range, "T_amb_bounds": t_amb_range,
             "steady_fraction": steady_fraction, "soak_bounds": soak_range,
             "segment_duration": segment_duration}
    options = {k: v for k, v in given.items() if v is not None}
    if cycle is not None or speed != 0.0:
        options.setdefault("speed_bounds", None)   # an explicit profile replaces the preset's
    if duration is not None:
        options["duration"] = duration
    spec = spec_for_model(model, signal=signal, seed=seed, speed=speed, cycle=cycle,
                          min_dwell=min_dwell, max_dwell=max_dwell, noise=noise,
                          vary_exogenous=vary_exogenous, design=design, **options)
    if cycle is not None:
        from acid.signals import drive_cycle

        drive_cycle(cycle, n=1, Ts=spec.Ts)  # unknown names fail before the plant is built
    the_plant = build_plant(plant, spec, params, plant_config, t_amb, fmu_map, allow_unstable,
                            refrigerant)
    identity = plant_identity(getattr(the_plant, "cfg", None),
                              vehicle_label(plant_config_given) if plant == "hifi" else plant)
    t0 = time.perf_counter()
    with progress_bar(f"exciting {plant} plant", spec.n_samples) as update:
        ds = run_excitation(the_plant, spec, progress=update)
    elapsed = time.perf_counter() - t0
    ds.validate()
    ds.to_hdf5(out)
    identity = recorded_identity(identity, ds)
    print_table(f"{out}: {len(ds)} samples, {ds.duration:g} s at Ts = {ds.Ts:g} s, "
                f"plant {plant} ({identity_line(identity)}), seed {seed}",
                ["channel", "unit", "min", "mean", "max"], _summary_rows(ds))
    segs = ds.metadata.get("segments") or []
    if segs:
        soaks = [s["soak_degC"] for s in segs]
        say(f"{len(segs)} pull-downs ({sum(s['kind'] == 'cold' for s in segs)} from a cold "
            f"soak at the ambient), soaks {min(soaks):.1f}-{max(soaks):.1f} degC, full-power "
            f"holds {min(s['full_power_s'] for s in segs):g}-"
            f"{max(s['full_power_s'] for s in segs):g} s")
    write_summary(json_out, {
        "command": "excite", "out": str(out), "plant": plant, **identity, "samples": len(ds),
        "duration_s": ds.duration, "Ts_s": ds.Ts, "seed": seed, "elapsed_s": elapsed,
        "excitation": spec.to_dict(),
        **({"segments": ds.metadata["segments"]} if "segments" in ds.metadata else {}),
        "ranges": {n: {"unit": ds.units[n], "min": float(np.min(v)), "max": float(np.max(v))}
                   for n, v in ds.channels.items()},
    })
