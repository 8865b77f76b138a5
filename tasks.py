"""Project tasks (pyinvoke). `invoke --list` shows them.

Task bodies live in toolchain/tasks/*.py, one module per area; toolchain
settings live in toolchain/*.toml, not in code. This file only lists them.
"""

from invoke import Collection

from toolchain.tasks import core, cross, firmware, link, sim, sweep, view

ns = Collection(
    core.build,
    core.test,
    core.lint,
    core.format,
    core.clean,
    core.bench,
    cross.cross_build,
    link.fuzz,
    sim.sim,
    sim.sim_acceptance,
    sim.allan_settings,
    sim.allan_sweep,
    sweep.sweep,
    view.view_soak,
    view.view_soak_clients,
    view.view_firmware,
    view.view_screenshot,
    Collection("firmware", firmware.build, firmware.sim),
)
