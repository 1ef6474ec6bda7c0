"""The JSON Schema of ``report.json`` and its validation.

Owns loading the shipped schema ``prs_geom/exports/schemas/report.schema.json`` (draft 2020-12,
``$id`` ``urn:prs-geom:report:1``; it describes ``format_version`` 1, see
:data:`prs_geom.exports.report.REPORT_FORMAT_VERSION`) and checking a report against it. A change
to the layout of report.json belongs in the schema too; the test suite validates every
build against it.
"""
from __future__ import annotations

import copy
import json
from functools import lru_cache
from importlib import resources
from typing import Any

import jsonschema
from jsonschema.exceptions import best_match

__all__ = ["SCHEMA_PACKAGE", "SCHEMA_NAME", "load_schema", "validate_report"]

SCHEMA_PACKAGE = "prs_geom.exports.schemas"
SCHEMA_NAME = "report.schema.json"


@lru_cache(maxsize=1)
def _schema() -> dict[str, Any]:
    text = resources.files(SCHEMA_PACKAGE).joinpath(SCHEMA_NAME).read_text(encoding="utf-8")
    return json.loads(text)


def load_schema() -> dict[str, Any]:
    """The report schema as a dict (read once from the package data; a copy on each call,
    so callers may change it)."""
    return copy.deepcopy(_schema())


@lru_cache(maxsize=1)
def _validator() -> jsonschema.Draft202012Validator:
    schema = _schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def validate_report(report: dict[str, Any]) -> None:
    """Raise :class:`jsonschema.ValidationError` if ``report`` does not follow the schema.

    The message starts with the JSON path of the failing key (e.g.
    ``$.loads.ldc_nut_roller[3]``) and names the rule it breaks; of several errors the most
    relevant one is raised (:func:`jsonschema.exceptions.best_match`) and the count of the
    others is added.
    """
    errors = list(_validator().iter_errors(report))
    if not errors:
        return
    err = best_match(errors)
    more = f" (and {len(errors) - 1} more error{'s' if len(errors) > 2 else ''})" if len(errors) > 1 else ""
    err.message = f"report.json {err.json_path}: {err.message}{more}"
    raise err
