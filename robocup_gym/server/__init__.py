"""``robocup-gym serve``: the embedded world as a drop-in for rcssserver3d 0.7.3.

Agents written for rcssserver3d (any language) connect to the agent port, RoboViz and trainer
scripts to the monitor port, unchanged. See ``docs/serve.md``.

Example (in-process, e.g. in a test)::

    from robocup_gym.server import SimServer

    server = SimServer(agent_port=0, monitor_port=0, host="127.0.0.1", sync=True, real_time=False)
    agent_port, monitor_port = server.start_in_thread()
    ...
    server.stop()
"""

from robocup_gym.server.server import PortInUseError, SimServer, serve

__all__ = ["PortInUseError", "SimServer", "serve"]
