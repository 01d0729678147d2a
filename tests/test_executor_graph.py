"""``acid reproduce`` as a task graph: the "where the energy is" study is one independent task
per drive cycle (they run side by side on the workers), and the ``cav`` stage that writes the
study's figures and summary waits for all of them."""

from __future__ import annotations

from acid.claims.options import ReproduceOptions
from acid.studies.reproduce import build_stages, cav_cycle_stage


def test_the_cav_study_is_one_independent_task_per_cycle():
    for opts in (ReproduceOptions(), ReproduceOptions.quick()):
        stages = {s.name: s for s in build_stages(opts)}
        cycles = [cav_cycle_stage(c) for c in opts.cav_cycles]
        assert len(cycles) >= 2 and all(c in stages for c in cycles)
        for c in cycles:  # each needs only the two models, never another cycle
            assert set(stages[c].depends) == {"fit", "econ"}
        assert set(cycles) <= set(stages["cav"].depends)
        # the cycle tasks share the study's options; only the cycle differs
        configs = [dict(stages[c].config) for c in cycles]
        assert len({c.pop("cycle") for c in configs}) == len(cycles)
        assert all(c == configs[0] for c in configs)
        assert stages["cav"].config["cycles"] == list(opts.cav_cycles)


def test_the_engine_is_one_task_per_scenario_and_judges_after_all_of_them():
    from acid.studies.reproduce import engine_scenarios, engine_stage

    for opts in (ReproduceOptions(), ReproduceOptions.quick()):
        stages = {s.name: s for s in build_stages(opts)}
        config = stages["engine"].config
        training, held = engine_scenarios(config)
        assert len(training) == len(held) == len(opts.engine_cycles or config["cycles"])
        train = [engine_stage("train", n) for n in training]
        judged = [engine_stage("held", n) for n in held]
        for t in train:   # training needs only the econ model
            assert stages[t].depends == ("econ",)
        for j in judged:  # a held-out task needs the knobs tuned on every training task
            assert set(stages[j].depends) == {"econ", *train}
        plans = [f"plan_{c}" for c in config["plan_cycles"]]
        assert set(stages["engine"].depends) == {"econ", *train, *judged, *plans}
        assert all(stages[p].depends == ("econ",) for p in plans)
        assert not set(train) & set(judged)
