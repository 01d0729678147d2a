"""FMI 2.0 / 3.0: any co-simulation FMU as a plant (:mod:`acid.plant.fmi.plant`, ``--plant
fmu:PATH``) and acid's own plant exported as an FMU (:mod:`acid.plant.fmi.export`, ``acid
export-fmu``; slave code :mod:`acid.plant.fmi._slave`)."""
