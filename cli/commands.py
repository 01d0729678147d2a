"""Registration of the sub-commands (each lives in its own module of ``acid_cli``).

One block per command module, in pipeline order: the plant study, data in, identification,
validation, control, and the whole paper.
"""

from __future__ import annotations


def register(app) -> None:
    """Add every sub-command to ``app`` (``acid_cli.main.app``), in pipeline order."""
    from acid_cli import (
        excite,
        fit,
        import_data,
        mpc_check,
        reproduce,
        speed_sweep,
        validate,
    )

    app.command(name="speed-sweep")(speed_sweep.speed_sweep)
    app.command(name="excite")(excite.excite)
    app.command(name="import")(import_data.import_data)
    app.command(name="fit")(fit.fit)
    app.command(name="validate")(validate.validate)
    app.command(name="mpc-check")(mpc_check.mpc_check)
    app.command(name="reproduce")(reproduce.reproduce)

    from acid_cli import cav_study

    app.command(name="cav-study")(cav_study.cav_study)

    from acid_cli import claims

    app.command(name="claims")(claims.claims)

    from acid_cli import plant_check

    app.command(name="plant-check")(plant_check.plant_check)

    from acid_cli import heating_check

    app.command(name="heating-check")(heating_check.heating_check)

    from acid_cli import heating_control

    app.command(name="heating-control")(heating_control.heating_control)

    from acid_cli import export_fmu

    app.command(name="export-fmu")(export_fmu.export_fmu)

    from acid_cli import export_c

    app.command(name="export-c")(export_c.export_c_cmd)

    from acid_cli import sweep

    app.command(name="sweep")(sweep.sweep)

    from acid_cli import examples

    app.command(name="examples")(examples.examples)

    from acid_cli import year_sweep

    app.command(name="year-sweep")(year_sweep.year_sweep)

    from acid_cli import day

    app.command(name="day")(day.day)

    from acid_cli import compare

    app.command(name="compare")(compare.compare)

    from acid_cli import pulldown

    app.command(name="pulldown")(pulldown.pulldown)

    from acid_cli import car

    car_app = type(app)(name="car", no_args_is_help=True, cls=app.info.cls,   # acid's group:
                        # flags shown without a type, usage errors as one line
                        help="The car study on a folder of a car's logs: fit, validate, "
                             "control.")
    car_app.command(name="fit")(car.car_fit)
    car_app.command(name="validate")(car.car_validate)
    car_app.command(name="control")(car.car_control)
    car_app.command(name="select")(car.car_select)
    app.add_typer(car_app, name="car")
