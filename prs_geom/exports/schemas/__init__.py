"""JSON Schemas shipped with prs_geom (package data): ``report.schema.json`` describes
``report.json``; load it with :func:`prs_geom.report_schema.load_schema`."""

__all__ = []
