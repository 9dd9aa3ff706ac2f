"""Threads of the compiled step's element kernels (``[solver] threads``): the same states bit
for bit as one thread (the chunks' sums stay in chunk order), damped and undamped; a bad
thread count is a scene error naming the key."""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest

from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import parse_scene
from runtime.solve import engines
from runtime.studies.bench_steps import chain_scene, plate_scene


def _states(scene, threads: int) -> list[np.ndarray]:
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                 threads=threads))
    model = Model(scene)
    runner = engines.make("compiled", model, scene.dynamic, model.reference)
    assert runner.threads == threads
    states = []
    runner.run(scene.dynamic.t_end, scene.dynamic.step,
               lambda t, q, v: states.append(np.concatenate([q, v])))
    return states


@pytest.mark.parametrize("damping", [0.0, 1e-4])
def test_two_threads_give_one_threads_states_bit_for_bit(damping):
    scene = plate_scene(12, 5)           # 144 elements: three chunks of kernels
    scene = dataclasses.replace(scene, materials={name: dataclasses.replace(
        material, damping=damping) for name, material in scene.materials.items()})
    one, two = _states(scene, 1), _states(scene, 2)
    assert len(one) == len(two) > 1
    assert all(np.array_equal(a, b) for a, b in zip(one, two, strict=True))
    assert np.abs(one[-1] - one[0]).max() > 0.0


def test_a_banded_chain_on_two_threads_is_the_one_thread_chain():
    one, two = _states(chain_scene(200, 5), 1), _states(chain_scene(200, 5), 2)
    assert all(np.array_equal(a, b) for a, b in zip(one, two, strict=True))


@pytest.mark.parametrize("value", [0, -1, 1.5, "two", 65])
def test_a_bad_thread_count_is_a_scene_error(value):
    base = plate_scene(2, 1).to_dict()
    base["solver"] = {**base.get("solver", {}), "threads": value}
    with pytest.raises(SceneError, match=r"^solver\.threads: expected"):
        parse_scene(base)


def test_the_automatic_count_threads_kernel_heavy_models_only():
    # a 16 x 16 plate3d: 5.8e7 counted operations an evaluation, 98 per Jacobian entry;
    # a beam3d chain: 13 per entry (its scatter, in chunk order on one thread, would
    # dominate: measured 2.8x slower kernels on 2 threads), as a small plate (4e6)
    from runtime.model.dae import DAESystem
    from runtime.solve.compiled_engine import kernel_threads

    def automatic(scene) -> int:
        model = Model(scene)
        return kernel_threads(DAESystem(model, model.reference), None)

    cores = len(os.sched_getaffinity(0))
    assert automatic(plate_scene(16, 1)) == min(cores, 4)
    assert automatic(plate_scene(4, 1)) == automatic(chain_scene(2000, 1)) == 1
    assert kernel_threads(DAESystem(Model(plate_scene(4, 1)), Model(plate_scene(4, 1))
                                    .reference), 3) == 3
