"""The ``See`` perceptor's noise: SimSpark draws it group by group (the landmarks and the ball,
then each seen player's five parts, then the line end points), three ``normal(0, sigma, n)``
draws per group (distances in percent of the distance, then horizontal, then vertical angles)."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.sim.field import LANDMARKS
from robocup_gym.sim.vision import (
    DISTANCE_NOISE_PERCENT,
    HORIZONTAL_NOISE_DEG,
    PLAYER_PARTS,
    VERTICAL_NOISE_DEG,
    Observer,
    VisionConfig,
    see,
    see_many,
)


def _scene(seed: int):
    """A head at (−6, 0) looking roughly along +x, 22 players scattered before and around it."""
    rng = np.random.default_rng(seed)
    yaw, pitch = rng.uniform(-0.5, 0.5), rng.uniform(-0.4, 0.1)
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    # head frame: x right, y forward, z up; yaw 0 looks along world +x
    head_rot = (
        np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
        @ np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]])
        @ np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
    )
    players = []
    for k in range(22):
        centre = np.array([rng.uniform(-9, 6), rng.uniform(-6, 6), 0.3])
        players.append(
            ("A" if k < 11 else "B", k % 11 + 1, centre + rng.uniform(-0.2, 0.2, (5, 3)))
        )
    return {
        "head_pos": np.array([-6.0, 0.0, 0.5]),
        "head_rot": head_rot,
        "ball_pos": np.array([rng.uniform(-4, 4), rng.uniform(-3, 3), 0.04]),
        "players": players,
        "calibration": np.zeros(3),
    }


def _noisy(pol: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One group's noise as SimSpark draws it."""
    n = len(pol)
    d = rng.normal(0.0, DISTANCE_NOISE_PERCENT, n)
    h = rng.normal(0.0, HORIZONTAL_NOISE_DEG, n)
    v = rng.normal(0.0, VERTICAL_NOISE_DEG, n)
    out = pol.copy()
    out[:, 0] += d * out[:, 0] / 100.0
    out[:, 1] += h
    out[:, 2] += v
    return out


@pytest.mark.parametrize("seed", range(5))
def test_the_noise_is_drawn_group_by_group_in_simspark_s_order(seed):
    scene = _scene(seed)
    exact = see(**scene, rng=np.random.default_rng(0), config=VisionConfig(noise=False))
    noisy = see(**scene, rng=np.random.default_rng(seed), config=VisionConfig(noise=True))
    assert len(exact.players) > 3 and len(exact.lines) > 0  # the scene shows every group

    rng = np.random.default_rng(seed)
    # the objects' group has every landmark and the ball, seen or not: the noise-free percept
    # has the seen ones only, so the draw is checked on those rows
    names = (*LANDMARKS, "B")
    n_obj = len(names)
    d = rng.normal(0.0, DISTANCE_NOISE_PERCENT, n_obj)
    h = rng.normal(0.0, HORIZONTAL_NOISE_DEG, n_obj)
    v = rng.normal(0.0, VERTICAL_NOISE_DEG, n_obj)
    assert set(noisy.objects) == set(exact.objects)
    for i, name in enumerate(names):
        if name in exact.objects:
            pol = exact.objects[name]
            expected = pol + np.array([d[i] * pol[0] / 100.0, h[i], v[i]])
            np.testing.assert_allclose(noisy.objects[name], expected, rtol=0, atol=1e-12)

    assert [(p.team, p.unum) for p in noisy.players] == [(p.team, p.unum) for p in exact.players]
    for seen_noisy, seen_exact in zip(noisy.players, exact.players, strict=True):
        # every part is in the draw; only the visible ones are in the percept
        parts = np.array([seen_exact.parts.get(k, np.full(3, 1.0)) for k in PLAYER_PARTS])
        expected = _noisy(parts, rng)
        assert list(seen_noisy.parts) == list(seen_exact.parts)
        for i, k in enumerate(PLAYER_PARTS):
            if k in seen_exact.parts:
                np.testing.assert_allclose(seen_noisy.parts[k], expected[i], rtol=0, atol=1e-12)

    expected_lines = _noisy(exact.lines.reshape(-1, 3), rng).reshape(-1, 2, 3)
    np.testing.assert_allclose(noisy.lines, expected_lines, rtol=0, atol=1e-12)


def _same_vision(a, b) -> None:
    assert list(a.objects) == list(b.objects)
    for name in a.objects:
        np.testing.assert_allclose(a.objects[name], b.objects[name], rtol=0, atol=1e-12)
    assert [(p.team, p.unum, list(p.parts)) for p in a.players] == [
        (p.team, p.unum, list(p.parts)) for p in b.players
    ]
    for p, q in zip(a.players, b.players, strict=True):
        for k in p.parts:
            np.testing.assert_allclose(p.parts[k], q.parts[k], rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.lines, b.lines, rtol=0, atol=1e-12)
    assert (a.my_pos is None) == (b.my_pos is None) and a.my_orientation_deg == b.my_orientation_deg


@pytest.mark.parametrize(
    "config",
    [
        VisionConfig(),
        VisionConfig(noise=False, ground_truth=True),
        VisionConfig(view_cone_deg=360.0, lines=False),
    ],
)
def test_several_observers_see_as_each_alone_with_the_same_noise(config):
    """A game's players see together (one computation): the same percepts and the same noise
    numbers, in the same order, as each observer seeing after the other."""
    scenes = [_scene(seed) for seed in range(6)]
    players, ball = scenes[0]["players"], scenes[0]["ball_pos"]
    rng = np.random.default_rng(3)
    observers = []
    for k, scene in enumerate(scenes):
        head = scene["head_pos"] + np.array([k * 2.0, k - 3.0, 0.0])
        observers.append(
            Observer(head, scene["head_rot"], rng.uniform(-0.005, 0.005, 3), k % 2 == 1)
        )
    one_by_one, together = np.random.default_rng(7), np.random.default_rng(7)
    alone = [
        see(
            head_pos=o.head_pos,
            head_rot=o.head_rot,
            ball_pos=ball,
            players=players,
            calibration=o.calibration,
            rng=one_by_one,
            config=config,
            mirror=o.mirror,
        )
        for o in observers
    ]
    seen = see_many(observers, ball_pos=ball, players=players, rng=together, config=config)
    assert sum(len(v.players) for v in seen) > 10 and any(len(v.objects) > 2 for v in seen)
    for a, b in zip(alone, seen, strict=True):
        _same_vision(a, b)
    assert one_by_one.standard_normal() == together.standard_normal()  # as many numbers drawn
    assert see_many([], ball_pos=ball, players=players, rng=together, config=config) == []
