"""The high-fidelity plant stepped for B scenarios at once: :class:`BatchPlant`
(:mod:`acid.plant.batch.plant`), bit-compatible with ``acid.plant.hifi.HifiPlant`` to rounding."""

from acid.plant.batch.plant import (
    CYCLE_FIELDS,
    INITIAL_KEYS,
    SHARED_FIELDS,
    BatchCycle,
    BatchPlant,
    CycleParams,
)

__all__ = ["CYCLE_FIELDS", "INITIAL_KEYS", "SHARED_FIELDS", "BatchCycle", "BatchPlant",
           "CycleParams"]
