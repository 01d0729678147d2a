"""Plants: the high-fidelity A/C + cabin simulator and the control-oriented model as a plant.

Both implement the protocol of ``acid.plant.base.Plant`` (reset / step / simulate).
"""

from acid.plant.base import InputSchedule, Measurement, Plant, measurements_to_dataset
from acid.plant.model_plant import ModelPlant

__all__ = ["InputSchedule", "Measurement", "ModelPlant", "Plant", "make_plant",
           "measurements_to_dataset"]


def make_plant(name: str, *, config_path=None, params=None, meas_noise_std: float = 0.0,
               process_noise_std: float = 0.0, rng=None, T_amb: float | None = None) -> Plant:
    """The plant chosen by ``--plant``: ``"hifi"`` (high-fidelity, default) or ``"model"``.

    ``config_path`` is a TOML plant configuration (hifi); ``params`` the model parameters
    (model plant); noise levels in K; ``T_amb`` in K overrides the ambient temperature.
    """
    from acid.errors import ConfigError

    if name == "model":
        kw = {} if T_amb is None else {"T_amb": T_amb}
        return ModelPlant(params=params, meas_noise_std=meas_noise_std,
                          process_noise_std=process_noise_std, rng=rng, **kw)
    if name == "hifi":
        from acid.plant.config import PlantConfig
        from acid.plant.hifi import HifiPlant

        cfg = PlantConfig.from_toml(config_path) if config_path else PlantConfig()
        if T_amb is not None:
            cfg = cfg.replace(T_amb=T_amb)
        return HifiPlant(cfg, meas_noise_std=meas_noise_std, rng=rng)
    raise ConfigError(f"--plant: unknown plant {name!r} (choose 'hifi' or 'model')")
