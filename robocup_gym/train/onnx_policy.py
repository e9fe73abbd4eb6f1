"""An exported policy file: an ONNX graph from observation to action with the description
the export wrote into it (:class:`OnnxPolicy`, run with ONNX Runtime, no torch needed)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "INPUT_NAME",
    "METADATA_KEY",
    "OUTPUT_NAME",
    "OnnxPolicy",
    "one_thread_options",
    "read_metadata",
]

METADATA_KEY = "robocup_gym"
"""Key of the description in the ONNX file's metadata."""
INPUT_NAME = "obs"
OUTPUT_NAME = "action"


def read_metadata(onnx_path: str | os.PathLike) -> dict[str, Any]:
    """The ``robocup_gym`` metadata of an exported policy (from the ONNX file itself)."""
    import onnx

    proto = onnx.load(str(onnx_path), load_external_data=False)
    for p in proto.metadata_props:
        if p.key == METADATA_KEY:
            return json.loads(p.value)
    sidecar = Path(onnx_path).with_suffix(".json")
    if sidecar.exists():
        return json.loads(sidecar.read_text())
    raise ValueError(f"{onnx_path} carries no robocup_gym metadata (not exported by robocup-gym?)")


def one_thread_options(ort):
    """Session options for a small policy network: one thread, which does not spin while it
    waits. ONNX Runtime's default (a thread per core, spinning between calls) takes a core from
    every other process of a machine whose cores are all busy with simulation (the training
    workers), for no gain on matrices this small."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    return options


class OnnxPolicy:
    """An exported policy: ``policy(obs) → action`` with ONNX Runtime (no torch needed)."""

    def __init__(self, onnx_path: str | os.PathLike) -> None:
        import onnxruntime as ort

        self.path = Path(onnx_path)
        try:
            self.session = ort.InferenceSession(
                str(self.path),
                sess_options=one_thread_options(ort),
                providers=["CPUExecutionProvider"],
            )
            self.metadata = read_metadata(self.path)
        except ValueError:
            raise
        except Exception as exc:  # protobuf/runtime errors of a bad file
            first = (str(exc).strip().splitlines() or [""])[0]
            raise ValueError(
                f"{self.path} is not a valid ONNX policy ({type(exc).__name__}: {first[:200]}); "
                "make one with `robocup-gym export RUN --onnx FILE`"
            ) from None

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float32)
        single = x.ndim == 1
        if single:
            x = x[None]
        y = self.session.run([OUTPUT_NAME], {INPUT_NAME: x})[0]
        return y[0] if single else y
