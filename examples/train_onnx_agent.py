"""Drive a Nao on an rcssserver3d-protocol server with an exported policy.

Start a server with ground truth (the kick policies observe the ball position), then run::

    robocup-gym serve --ground-truth --sync --no-real-time &
    python examples/train_onnx_agent.py kick.onnx --port 3100 --monitor-port 3200

This is what ``robocup-gym agent kick.onnx`` does. In a team's own agent the same two pieces are
used: build the observation (``policy.json`` next to the ONNX file lists its layout) and call
``OnnxPolicy(path)(obs)`` for the action (joint velocities are ``action * max speed``).
"""

from __future__ import annotations

import argparse

from robocup_gym.train.agent import run_onnx_agent


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("onnx")
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=3100)
    p.add_argument("--monitor-port", type=int, default=3200)
    p.add_argument("--episodes", type=int, default=3)
    args = p.parse_args()
    for rep in run_onnx_agent(
        args.onnx,
        host=args.host,
        port=args.port,
        monitor_port=args.monitor_port,
        episodes=args.episodes,
    ):
        print(f"{rep.steps} steps, fallen={rep.fallen}, ball moved {rep.ball_displacement}")


if __name__ == "__main__":
    main()
