"""Plants: the high-fidelity A/C + cabin simulator, the control-oriented model as a plant, and
any FMI 2.0 / 3.0 co-simulation FMU (``acid.plant.fmi.plant``).

All implement the protocol of ``acid.plant.base.Plant`` (reset / step / measure / simulate).
"""

from acid.plant.base import InputSchedule, Measurement, Plant, measurements_to_dataset


def ModelPlant(params=None, **kw):  # noqa: N802 - the plant's public name since the start
    """The paper's model as a plant: ``acid.plant.declared.paper_plant`` (a ``DeclaredPlant``)."""
    from acid.plant.declared import paper_plant

    return paper_plant(params, **kw)


__all__ = ["FMU_PREFIX", "InputSchedule", "Measurement", "ModelPlant", "Plant", "make_plant",
           "measurements_to_dataset"]


#: Prefix of an FMU plant in ``--plant`` / ``make_plant``: ``"fmu:PATH.fmu"``.
FMU_PREFIX = "fmu:"


def make_plant(name: str, *, config_path=None, params=None, meas_noise_std: float = 0.0,
               process_noise_std: float = 0.0, rng=None, T_amb: float | None = None,
               fmu_map=None, mode: str = "direct", refrigerant: str | None = None) -> Plant:
    """The plant chosen by ``--plant``: ``"hifi"`` (high-fidelity, default), ``"model"`` or
    ``"fmu:PATH.fmu"`` (an FMI co-simulation FMU driven through the map ``fmu_map``).

    ``config_path`` is a TOML plant configuration or a vehicle name (hifi; ``"paper"``, the
    Table I calibration, or ``"default"``, see ``acid.plant.vehicles``); ``params`` the model
    parameters (model plant); noise levels in K; ``T_amb`` in K overrides the ambient temperature;
    ``mode`` is "direct" (inputs commanded) or "nominal" (the plant's own controller; hifi
    and FMU plants); ``refrigerant`` overrides the configuration's (hifi only).
    """
    from acid.errors import ConfigError

    if T_amb is not None and not 200.0 < float(T_amb) < 400.0:
        raise ConfigError(f"ambient temperature T_amb = {T_amb} is not plausible in kelvin "
                          "(give kelvin, or acid.degC(...))")
    if refrigerant is not None and name != "hifi":
        raise ConfigError(f"--refrigerant applies to --plant hifi only, not {name!r}")
    if name.startswith(FMU_PREFIX):
        from acid.plant.fmi.plant import FmuPlant

        path = name[len(FMU_PREFIX):]
        if not path:
            raise ConfigError("--plant fmu:PATH: the FMU path is missing")
        if fmu_map is None:
            raise ConfigError(f"--plant {name}: an FMU plant needs --fmu-map MAP.toml")
        return FmuPlant(path, fmu_map, mode=mode, meas_noise_std=meas_noise_std, rng=rng,
                        T_amb=T_amb)
    if fmu_map is not None:
        raise ConfigError("--fmu-map applies to --plant fmu:PATH.fmu only")
    if name == "model":
        kw = {} if T_amb is None else {"T_amb": T_amb}
        return ModelPlant(params=params, meas_noise_std=meas_noise_std,
                          process_noise_std=process_noise_std, rng=rng, **kw)
    if name == "hifi":
        from acid.plant.hifi import HifiPlant
        from acid.plant.vehicles import vehicle_config

        cfg = vehicle_config(config_path or None)
        if T_amb is not None:
            cfg = cfg.replace(T_amb=T_amb)
        if refrigerant is not None:
            cfg = cfg.replace(refrigerant=refrigerant)
        return HifiPlant(cfg, mode=mode, meas_noise_std=meas_noise_std, rng=rng)
    raise ConfigError(f"--plant: unknown plant {name!r} (choose 'hifi', 'model' or "
                      "'fmu:PATH.fmu')")
