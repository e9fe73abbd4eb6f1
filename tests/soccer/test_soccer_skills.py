"""Skills as actions: players walk at the commanded velocity with the shipped walk policy, kick
with the scripted kick and get up by themselves with the shipped get-up policy."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pettingzoo")
pytest.importorskip("onnxruntime")

from pettingzoo.test import parallel_api_test

from robocup_gym.sim.engines.ode import available
from robocup_gym.sim.rotations import axis_angle_quat, quat_multiply, yaw_quat
from robocup_gym.soccer import game_v0, game_v1, penalty_v1
from robocup_gym.soccer.skills import SKILL_ACTION_LABELS

pytestmark = pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")


@pytest.fixture
def solo():
    """One left player of type 0 with skill actions, nobody else."""
    env = game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), max_cycles=10**5)
    yield env
    env.close()


def test_skill_actions_pass_the_api_test_and_name_their_values():
    env = penalty_v1.parallel_env(actions="skills", max_cycles=200)
    assert env.action_space("left_1").shape == (len(SKILL_ACTION_LABELS),)
    parallel_api_test(env, num_cycles=30)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"right_1: action value 3 \(kick\) is inf"):
        env.step({"left_1": np.zeros(4), "right_1": np.array([0, 0, 0, np.inf])})
    with pytest.raises(ValueError, match=r"expected \(4,\) \(a skill action: forward"):
        env.step({"left_1": np.zeros(22), "right_1": np.zeros(4)})
    env.close()


def test_a_player_walks_where_it_is_told(solo):
    solo.reset(seed=0)
    w = solo.game.world
    start = w.torso_position(0).copy()
    for _ in range(25):  # 5 s at 0.5 m/s forward (the left team faces +x)
        solo.step({"left_1": np.array([0.625, 0.0, 0.0, 0.0])})
    moved = w.torso_position(0) - start
    assert moved[0] > 2.0, moved
    assert abs(moved[1]) < 1.0, moved
    assert solo.skills.modes() == ["walk"]
    assert w.torso_position(0)[2] > 0.3  # still up


OMNIDIRECTIONAL = {"walk": "walk", "walk_faces_x": False}
"""A game's options that play the omnidirectional walk."""


@pytest.mark.parametrize(
    ("module", "options"),
    [(game_v1, {}), (game_v0, {}), (game_v1, OMNIDIRECTIONAL)],
    ids=["v1", "v0", "v1, the omnidirectional walk"],
)
def test_a_player_facing_the_other_way_walks_and_turns_as_told(module, options):
    """The game's walk was trained facing +x and observes its torso's orientation in the world
    frame; from ``game_v1`` on (``walk_faces_x``) it sees every player as if it faced +x.
    Facing −x it then walks straight and turns clockwise; ``game_v0``'s walk went askew and
    hardly turned. The omnidirectional walk (``walk="walk"``), trained turning through every
    heading, sees the player as it faces and walks and turns as told too."""
    from robocup_gym.envs.observations import heading_frame, turn_to_deg

    env = module.parallel_env(
        actions="skills", left_types=(0,), right_types=(), max_cycles=10**5, **options
    )
    assert env.skills.walk_policy.path.stem == options.get("walk", "game-walk")
    env.reset(seed=0)
    env.game.referee.set_play_mode("PlayOn")
    w = env.game.world
    w.place_robot(0, 5.0, 0.0, heading_deg=180.0)
    start = w.torso_position(0).copy()
    for _ in range(25):  # 5 s at 0.5 m/s forward, along -x
        env.step({"left_1": np.array([0.625, 0.0, 0.0, 0.0])})
    moved = w.torso_position(0) - start
    assert env.skills.modes() == ["walk"]
    env.reset(seed=0)  # placed mid-stride, the robot falls
    env.game.referee.set_play_mode("PlayOn")
    w.place_robot(0, 5.0, 0.0, heading_deg=180.0)
    for _ in range(25):  # 5 s turning clockwise at 30 deg/s
        env.step({"left_1": np.array([0.0, 0.0, -1.0, 0.0])})
    turned = -turn_to_deg(heading_frame(w.torso_quat(0)), np.pi)  # from facing -x, deg
    assert env.skills.modes() == ["walk"]
    env.close()
    if module is game_v1:
        sets_off = "walk" in options  # the omnidirectional walk sets off over 1 s
        assert moved[0] < (-2.1 if sets_off else -2.4) and abs(moved[1]) < 0.5, moved
        assert turned < -40.0, turned
    else:
        assert abs(moved[1]) > 0.6 or turned > -20.0, (moved, turned)


def test_a_player_kicks_a_ball_in_front_of_its_right_foot(solo):
    solo.reset(seed=0)
    w = solo.game.world
    for _ in range(10):  # stand for 2 s
        solo.step({"left_1": np.zeros(4)})
    p = w.torso_position(0)
    solo.game.host.set_ball((p[0] + 0.12, p[1] - 0.055, 0.041), (0.0, 0.0, 0.0))
    before = w.ball_position().copy()
    solo.step({"left_1": np.array([0.0, 0.0, 0.0, 1.0])})
    assert solo.skills.modes() in (["kick"], ["get-up"], ["walk"])
    for _ in range(15):
        solo.step({"left_1": np.zeros(4)})
    moved = w.ball_position() - before
    assert moved[0] > 1.0, moved  # forward, as the robot faces


@pytest.mark.parametrize("self_collisions", [False, True], ids=["no rule", "self-collision rule"])
def test_a_fallen_player_gets_up_by_itself(self_collisions):
    """With the self-collision rule (a real server's, ``serve``'s) the get-up plays GetUp-v1's
    scripts alone; without it, the shipped get-up policy over the same scripts."""
    solo = game_v1.parallel_env(
        actions="skills",
        left_types=(0,),
        right_types=(),
        max_cycles=10**5,
        self_collisions=self_collisions,
    )
    assert solo.game.world.self_collision_rule is self_collisions
    assert (solo.skills.uses_policy["get-up"] == set()) is self_collisions
    solo.reset(seed=0)
    w = solo.game.world
    lying = quat_multiply(yaw_quat(np.radians(-90.0)), axis_angle_quat((1, 0, 0), np.radians(-90)))
    w.place_robot(0, -14.0, 0.0, z=0.1, quat=lying, joint_angles_deg=np.zeros(22))
    heights, modes = [], []
    for _ in range(30):  # 6 s, told to stand (a second try from the other side included)
        solo.step({"left_1": np.zeros(4)})
        heights.append(float(w.torso_position(0)[2]))
        modes.append(solo.skills.modes()[0])
    assert "get-up" in modes
    assert min(heights) < 0.15 and heights[-1] > 0.3, heights
    assert modes[-1] == "walk"
    assert solo.skills.players[0].getup.env.config.self_collisions  # GetUp-v1's scripts
    solo.close()


def test_skill_games_repeat_from_their_seed():
    def run():
        env = game_v1.parallel_env(
            actions="skills", left_types=(0, 4), right_types=(1,), max_cycles=200
        )
        rng = np.random.default_rng(1)
        obs, _ = env.reset(seed=5)
        out = [np.concatenate(list(obs.values()))]
        while env.agents:
            acts = {a: rng.uniform(-1, 1, 4) for a in env.agents}
            obs, *_ = env.step(acts)
            out.append(np.concatenate(list(obs.values())))
        env.close()
        return np.concatenate(out)

    assert np.array_equal(run(), run())


@pytest.fixture
def nod():
    """A motion skill registered for the test: the head turns at ``speed`` rad/s (its one
    parameter) for 15 cycles."""
    from robocup_gym.robot.nao import nao_model
    from robocup_gym.soccer.motions import (
        ScriptedMotion,
        register_motion_skill,
        unregister_motion_skill,
    )

    def start(robot_type: int, speed: float) -> ScriptedMotion:
        row = np.zeros(len(nao_model(robot_type).effector_names))
        row[0] = speed  # he1, rad/s
        return ScriptedMotion([row] * 15)

    register_motion_skill("look", start, "the head turned", parameters=("speed",))
    yield "look"
    unregister_motion_skill("look")


def test_a_registered_motion_skill_becomes_an_action(nod):
    """A game whose ``skills`` list a registered motion has its values in the actions: one
    that starts the motion and one per parameter; the motion runs to its end and the player
    walks again; the scripted team's actions are fitted to the game's (its kick kept, no other
    motion started)."""
    from robocup_gym.soccer.scripted import ScriptedTeam

    env = game_v1.parallel_env(
        actions="skills", left_types=(0,), right_types=(), max_cycles=10**5, skills=("kick", nod)
    )
    try:
        assert env.action_space("left_1").shape == (6,)
        labels = ("forward", "left", "turn", "kick", "look", "look.speed")
        assert env.skill_action_labels == labels
        env.reset(seed=0)
        player = env.skills.players[0]
        for _ in range(5):
            env.step({"left_1": np.zeros(6)})
        for speed in (-1.0, 0.5):
            head = player.backend.perception.joint("hj1")
            env.step({"left_1": np.array([0.0, 0.0, 0.0, 0.0, 1.0, speed])})  # 10 cycles of 15
            assert env.skills.modes() == ["look"]
            turned = player.backend.perception.joint("hj1") - head
            expected = speed * 10 * 0.02 * 180.0 / np.pi  # at most 10 cycles at the speed, deg
            assert 0.7 * abs(expected) < speed * turned / abs(speed) <= abs(expected), turned
            env.step({"left_1": np.zeros(6)})
            assert env.skills.modes() == ["walk"]
        with pytest.raises(ValueError, match=r"expected \(6,\) \(a skill action: forward, left, "):
            env.step({"left_1": np.zeros(4)})
        acts = ScriptedTeam()(env, ["left_1"])
        assert acts["left_1"].shape == (6,) and acts["left_1"][4] == -1.0
        env.step(acts)
    finally:
        env.close()


def test_motion_skills_are_checked_by_name(nod):
    from robocup_gym.soccer.motions import (
        ScriptedMotion,
        motion_skills,
        register_motion_skill,
        unregister_motion_skill,
    )

    assert set(motion_skills()) >= {"kick", nod}
    with pytest.raises(ValueError, match=r"no motion skill 'dive'; registered: .*kick"):
        game_v1.parallel_env(actions="skills", skills=("kick", "dive"))
    with pytest.raises(ValueError, match="lists a motion skill twice"):
        game_v1.parallel_env(actions="skills", skills=("kick", "kick"))
    with pytest.raises(ValueError, match="sequence of motion skill names"):
        game_v1.parallel_env(actions="skills", skills="kick")
    with pytest.raises(ValueError, match="registered already"):
        register_motion_skill(nod, lambda t: None)
    # a motion whose command is not one finite velocity per joint: named
    register_motion_skill("bad", lambda t: ScriptedMotion([np.zeros(3)]))
    env = game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), skills=["bad"])
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match=r"motion skill 'bad' of player 0: .* 22 finite"):
            env.step({"left_1": np.array([0.0, 0.0, 0.0, 1.0])})
    finally:
        env.close()
        unregister_motion_skill("bad")
    for taken in ("turn", "get-up"):
        with pytest.raises(ValueError, match="taken by the walk or the get-up"):
            register_motion_skill(taken, lambda t: None)


def test_a_game_without_the_kick_has_only_the_walk():
    env = game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), skills=())
    try:
        assert env.action_space("left_1").shape == (3,)
        env.reset(seed=0)
        env.step({"left_1": np.array([0.0, 0.0, 1.0])})
        assert env.skills.modes() == ["walk"]
    finally:
        env.close()


def test_a_game_plays_the_motion_skills_its_learnt_teams_were_trained_with():
    from types import SimpleNamespace

    from robocup_gym.soccer.scripted import ScriptedTeam
    from robocup_gym.soccer.skills import fit_skill_action, skills_of_teams

    scripted, old = ScriptedTeam(), SimpleNamespace(options={"privileged": True})
    assert skills_of_teams(scripted, old) == ("kick",)  # no team says: the default
    trained = SimpleNamespace(options={"skills": ["kick", "look"]})
    assert skills_of_teams(scripted, trained) == ("kick", "look")
    with pytest.raises(ValueError, match="trained with different motion skills"):
        skills_of_teams(trained, SimpleNamespace(options={"skills": []}))
    labels = ("forward", "left", "turn", "look", "look.speed")
    np.testing.assert_array_equal(
        fit_skill_action([0.5, -0.2, 0.1, 1.0], labels), [0.5, -0.2, 0.1, -1.0, -1.0]
    )


def test_a_walk_with_a_command_loop_is_refused_a_turned_view():
    """The omnidirectional ``walk`` holds its heading with a command loop; seen turned to face
    +x it would hold nothing: the skill set says so, and takes it with ``walk_faces_x=False``."""
    from robocup_gym.soccer.skills import SkillSet

    with pytest.raises(ValueError, match="walk_faces_x=False"):
        SkillSet([0], walk="walk")
    skills = SkillSet([0], walk="walk", walk_faces_x=False)
    assert skills.walk_policy.metadata["env_config"]["command_feedback_gain"] > 0
    assert SkillSet([0]).walk_policy.path.stem == "game-walk"
    with pytest.raises(ValueError, match="walk_faces_x=False"):
        game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), walk="walk")
    with pytest.raises(ValueError, match="walk must be the name of a shipped walk"):
        game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), walk=3)
    for not_a_walk in ("run", "get-up", "penalty-striker"):  # shipped, but no walk
        with pytest.raises(ValueError, match=rf"'{not_a_walk}' is not a walk .* game-walk, walk"):
            SkillSet([0], walk=not_a_walk, walk_faces_x=False)


def test_a_player_walks_with_its_types_own_walk():
    """A Nao type with a walk of its own under the game's walk's name (``walk`` on type 3:
    the shared network over a narrower window) walks with it; the other types with the shared
    one; each policy's players in one batch. Both walk where they are told."""
    env = game_v1.parallel_env(
        actions="skills", left_types=(3, 0, 0), right_types=(), max_cycles=10**5, **OMNIDIRECTIONAL
    )
    try:
        skills = env.skills
        assert skills.walk_policies[0] is skills.walk_policy
        assert skills.walk_policies[3].path.name == "walk.type3.onnx"
        windows = [p.walk.env.config.target_around_start_deg for p in skills.players]
        assert windows == [26.0, 30.0, 30.0]
        batches = []

        def counted(policy):
            def act(obs):
                batches.append((policy.path.name, len(obs)))
                return policy(obs)

            return act

        skills.walk_policies = {t: counted(p) for t, p in skills.walk_policies.items()}
        env.reset(seed=0)
        w = env.game.world
        start = [w.torso_position(k).copy() for k in range(3)]
        for _ in range(25):  # 5 s at 0.5 m/s forward (the left team faces +x)
            env.step({a: np.array([0.625, 0.0, 0.0, 0.0]) for a in env.agents})
        for k in (0, 2):  # (the second player starts at the ball, and walks into it)
            moved = w.torso_position(k) - start[k]
            assert moved[0] > 2.0 and abs(moved[1]) < 1.0, (k, moved)
            assert w.torso_position(k)[2] > 0.3, k  # still up
        assert set(batches) == {("walk.onnx", 2), ("walk.type3.onnx", 1)}
    finally:
        env.close()


class _Stride:
    """A motion that walks forward at 0.3 m/s for ``walk`` cycles (its ``walk_command``), then
    holds every joint still for 10 cycles."""

    def __init__(self, robot_type: int, walk: int) -> None:
        from robocup_gym.robot.nao import nao_model

        self.walk, self.walked, self.played = walk, 0, 0
        self.size = len(nao_model(robot_type).effector_names)

    def walk_command(self, p):
        if self.walked == self.walk:
            return None
        self.walked += 1
        return np.array([0.3, 0.0, 0.0])

    def command(self, p):
        self.played += 1
        return np.zeros(self.size)

    @property
    def done(self) -> bool:
        return self.played >= 10


@pytest.fixture
def stride():
    """``stride`` registered for the test: 60 cycles of walking, then 10 of holding still."""
    from robocup_gym.soccer.motions import register_motion_skill, unregister_motion_skill

    started: list[_Stride] = []

    def start(robot_type: int) -> _Stride:
        started.append(_Stride(robot_type, 60))
        return started[-1]

    register_motion_skill("stride", start, "walk, then hold still")
    yield started
    unregister_motion_skill("stride")


def test_a_motion_that_steers_the_walk_walks_then_plays(stride):
    """A motion with ``walk_command`` walks the player with the game's walk while it returns
    commands (in the motion's mode), then plays its own commands to its end; an action that
    no longer starts it stops it while it walks."""
    env = game_v1.parallel_env(
        actions="skills", left_types=(0,), right_types=(), max_cycles=10**5, skills=("stride",)
    )
    try:
        env.reset(seed=0)
        w = env.game.world
        for _ in range(5):
            env.step({"left_1": np.zeros(4)})
        start = w.torso_position(0).copy()
        go = np.array([0.0, 0.0, 0.0, 1.0])
        for _ in range(6):  # 60 cycles of walking
            env.step({"left_1": go})
            assert env.skills.modes() == ["stride"]
        assert stride[-1].walked == 60 and stride[-1].played == 0
        assert w.torso_position(0)[0] - start[0] > 0.1  # it walked forward (+x)
        env.step({"left_1": go})  # the 10 cycles of its own
        assert stride[-1].played == 10
        assert env.skills.modes() == ["walk"]
        assert len(stride) == 1  # the action while it ran did not start another
        env.step({"left_1": go})  # a new one, stopped by a walk action while it walks
        assert env.skills.modes() == ["stride"] and len(stride) == 2
        env.step({"left_1": np.zeros(4)})
        assert env.skills.modes() == ["walk"]
        assert stride[-1].walked == 10 and stride[-1].played == 0
    finally:
        env.close()


def test_a_game_with_approach_kick_passes_the_api_test():
    """Random skill actions start, repeat and stop ``approach-kick`` (a motion that steers the
    walk) at random: the game keeps PettingZoo's parallel API."""
    env = game_v1.parallel_env(
        actions="skills",
        left_types=(0,),
        right_types=(1,),
        max_cycles=400,
        skills=("kick", "approach-kick"),
        **OMNIDIRECTIONAL,
    )
    assert env.skill_action_labels[-3:] == (
        "approach-kick", "approach-kick.distance", "approach-kick.direction"
    )  # fmt: skip
    parallel_api_test(env, num_cycles=40)
    env.close()
