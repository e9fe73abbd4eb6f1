"""Train a kick with PPO on RoboCup Gym's VelocityKick (Stable-Baselines3).

    python examples/train_velocity_kick.py --steps 200000 --workers 2

Roughly the RobocupGym paper's recipe (``v0001_ppo.py``): velocity actions, 40-step episodes,
20 wait steps, min–max observations clipped at 1, gSDE, a 2×256 network.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import SubprocVecEnv

import robocup_gym.envs  # noqa: F401  (registers RobocupGym/*)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--robot-type", type=int, default=0)
    parser.add_argument("--out", default="velocity_kick_ppo")
    args = parser.parse_args()

    env_kwargs = {"robot_type": args.robot_type, "max_episode_steps": 40, "wait_steps": 20}
    vec = make_vec_env(
        "RobocupGym/VelocityKick-v0",
        n_envs=args.workers,
        env_kwargs=env_kwargs,
        vec_env_cls=SubprocVecEnv if args.workers > 1 else None,
        seed=0,
    )
    model = PPO(
        "MlpPolicy",
        vec,
        n_steps=256,
        batch_size=128,
        learning_rate=1e-4,
        use_sde=True,
        policy_kwargs={"net_arch": [256, 256]},
        verbose=1,
        seed=0,
    )
    model.learn(total_timesteps=args.steps)
    model.save(args.out)

    # evaluate: how far does the ball go (SimpleKick measures after 200 wait cycles)?
    env = gym.make("RobocupGym/SimpleKick-v0", **{**env_kwargs, "wait_steps": 200})
    obs, _ = env.reset(seed=123)
    done = False
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    print(f"ball moved {reward:.2f} m (fallen: {info['fallen']})")


if __name__ == "__main__":
    main()
