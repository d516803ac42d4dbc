"""Workflow configuration files: read with located errors, checked against the schema.

Snakemake reads a ``--configfile`` before the workflow, and on a YAML syntax
error says only "Config file is not valid JSON or YAML".  :func:`read_config`
names the file, line and column; :func:`check_config` names the offending key
as the workflow does.  ``skinsuction check-config FILE`` runs both, merged over
the default configuration as Snakemake merges it.

Examples
--------
>>> import pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "bad.yaml"
>>> _ = path.write_text("mesh:\\n  refinement: [1, 2\\nspaces: {}\\n")
>>> read_config(path)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
skinsuction.errors.InputError: ...bad.yaml, line 3, column 7: not valid YAML (expected ',' or ']', but got ':')
>>> merge({"mesh": {"refinement": 1, "element": "quad8"}}, {"mesh": {"refinement": 2}})
{'mesh': {'refinement': 2, 'element': 'quad8'}}
"""

from __future__ import annotations

from pathlib import Path

from skinsuction.errors import InputError

__all__ = ["read_config", "merge", "key_error", "check_config", "DEFAULT_SCHEMA", "DEFAULT_CONFIG"]

#: Where the workflow keeps them, relative to the project's root.
DEFAULT_SCHEMA = Path("workflow/schemas/config.schema.yaml")
DEFAULT_CONFIG = Path("config/config.yaml")


def read_config(path) -> dict:
    """The mapping of a YAML (or JSON) file; InputError with file, line and column."""
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f", line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise InputError(f"{path}{where}: not valid YAML ({' '.join(str(problem).split())})") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise InputError(f"{path}: a configuration is a mapping of keys, got {type(data).__name__}")
    return data


def merge(base: dict, update: dict) -> dict:
    """``update`` over ``base``, recursively for mappings (as Snakemake merges configs)."""
    out = dict(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


def key_error(err) -> tuple[str, str]:
    """(dotted key, message) of a :class:`jsonschema.ValidationError`.

    For a ``oneOf`` the message adds what the deepest-matching alternative
    objects to, e.g. ``mesh.refinement``: "1.5 is not valid ... (e.g. 1.5 is
    greater than the maximum of 1)".
    """
    key = ".".join(map(str, err.absolute_path)) or "<top level>"
    message = err.message
    if err.context:
        best = max(err.context, key=lambda e: len(e.relative_path))
        message += f" (e.g. {best.message})"
    return key, message


def check_config(config: dict, schema_path=DEFAULT_SCHEMA, source: str = "config") -> None:
    """Validate ``config`` against the workflow's JSON schema (YAML file).

    Raises
    ------
    InputError
        ``"<source>: invalid configuration value for '<key>': <why>"``, the first
        error jsonschema finds (the most relevant by its ``best_match``).
    """
    import jsonschema

    schema = read_config(schema_path)
    validator = jsonschema.Draft202012Validator(schema)
    error = jsonschema.exceptions.best_match(validator.iter_errors(config))
    if error is not None:
        key, message = key_error(error)
        raise InputError(f"{source}: invalid configuration value for '{key}': {message}")
