"""The train command's options, made from :class:`~robocup_gym.train.config.TrainConfig`: one
``--field-name`` per field, typed as the field, its help the field's docstring."""

from __future__ import annotations

from typing import Annotated, Any

import typer

_NOT_TRAIN_OPTIONS = (
    "task",  # the command's argument
    "env_id",  # filled in by the trainer
    "env_config",
    "env_kwargs",  # --env KEY=VALUE
    "algo_kwargs",  # --hp KEY=VALUE
    "selfplay",  # --selfplay KEY=VALUE
    "backend",  # --engine / --backend
    "vec_env",  # --ray / --no-ray
    "ray_address",  # --ray-address (implies --ray)
)
"""TrainConfig fields the train command takes in its own way, not as ``--field-name``."""

_TRAIN_OPTION_EXTRAS: dict[str, dict[str, Any]] = {
    "assist_max_tilt_deg": {"flags": ("--assist-max-tilt-deg", "--assist-max-tilt")},
}
"""Option settings beyond the field's type: an extra flag name."""


def _option_help(doc: str, default: Any) -> str:
    """A field's docstring as an option's help: its first sentence, without reST markup, with
    the default."""
    import re

    text = " ".join(doc.split())
    text = re.sub(r":\w+:`~?([\w.]*\.)?([^`]+)`", r"\2", text)
    text = text.replace("``", "")
    m = re.match(r"(.+?[.])(\s|$)", text)
    first = m.group(1) if m else text
    if default in ("", None):
        return first
    return f"{first.rstrip('.')} (default: {default})."


def _train_config_parameters() -> list:
    """One keyword parameter of the train command per :class:`TrainConfig` field (but
    :data:`_NOT_TRAIN_OPTIONS`): ``--field-name``, typed as the field, help from its docstring,
    ``None`` when not given (the config file's or the default value then holds)."""
    import dataclasses
    import inspect
    import typing

    from robocup_gym.train.config import TrainConfig

    hints = typing.get_type_hints(TrainConfig)
    docs = TrainConfig.field_docs()
    params = []
    for f in dataclasses.fields(TrainConfig):
        if f.name in _NOT_TRAIN_OPTIONS:
            continue
        extra = dict(_TRAIN_OPTION_EXTRAS.get(f.name, {}))
        kind = extra.pop("type", hints[f.name])
        flag = "--" + f.name.replace("_", "-")
        flags = extra.pop("flags", (flag,))
        if kind is bool:
            flags = (f"{flag}/--no-{f.name.replace('_', '-')}",)
        default = f.default if f.default is not dataclasses.MISSING else None
        option = typer.Option(
            *flags, help=_option_help(docs.get(f.name, ""), default), show_default=False, **extra
        )
        params.append(
            inspect.Parameter(
                f.name,
                inspect.Parameter.KEYWORD_ONLY,
                default=None,
                annotation=Annotated[kind | None, option],
            )
        )
    return params


def _with_config_options(func):
    """``func`` (which takes ``**config``) with a typed parameter per TrainConfig field added
    to its signature, so that typer makes an option of each."""
    import inspect

    sig = inspect.signature(func, eval_str=True)
    own = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    own = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in own]
    params = own + _train_config_parameters()
    func.__signature__ = sig.replace(parameters=params)
    func.__annotations__ = {p.name: p.annotation for p in params}
    return func
