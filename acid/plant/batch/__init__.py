"""The high-fidelity plant stepped for B scenarios at once: :class:`BatchPlant`
(:mod:`acid.plant.batch.plant`), bit-compatible with ``acid.plant.hifi.HifiPlant`` to rounding."""

from acid.plant.batch.plant import CYCLE_FIELDS, INITIAL_KEYS, BatchCycle, BatchPlant

__all__ = ["CYCLE_FIELDS", "INITIAL_KEYS", "BatchCycle", "BatchPlant"]
