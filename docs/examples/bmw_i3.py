"""A real car's logs: the BMW i3 summer trips (TU Munich, doi:10.21227/6jr9-5235), imported
through acid's channel map, the shipped car_cabin model fitted on two trips by prediction
error and validated on a third beside persistence, ARX and subspace."""

import os
from pathlib import Path

import acid
from acid.ident.validate import fitted_parameters

LOGS = Path(os.environ.get("ACID_BMW_I3_LOGS", "../shared/real-data/bmw-i3"))

# the map: ';'-separated Latin-1 CSV at 10 Hz, km/h and kW, to 5 s means in SI units; it
# masks the cabin sensor's clipped samples (39.84 degC) so they are neither fitted nor scored
cmap = acid.ChannelMap.from_file(acid.example("bmw_i3_map.toml"))
est = acid.import_logs([LOGS / "TripA07.csv.gz", LOGS / "TripA12.csv.gz"], cmap)  # hot soaks
val = acid.import_logs([LOGS / "TripA08.csv.gz"], cmap)                           # held out
print(f"estimation: {len(est)} samples of {est.Ts:g} s from 2 trips, held out: {len(val)}")
print("channels:", ", ".join(est.channels))

# car_cabin: cabin air (measured), interior and shell (latent), an unlogged solar and
# occupant load that a Kalman filter follows; 25 gradient evaluations keep this page quick
fit = acid.fit_model("car_cabin", est, method="pem", max_nfev=25)
print(fit.summary())

# 10-minute predictions from 12 starts in the held-out trip, the latent states from the
# filter run from the trip's start; the yardsticks fitted on the two estimation trips
both, n = acid.Dataset.concatenate([est, val]), len(est)
res = acid.validate_model("car_cabin", both, fitted_parameters(fit), starts=12, horizon=120,
                          warmup=300, to_end=True, hold=(), warm_start="ekf-trip",
                          estimation=(0, n), start_range=(n, len(both)))
print(res.summary())
