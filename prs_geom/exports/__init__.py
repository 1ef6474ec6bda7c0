"""Files for people and tools.

Owns atomic output folders that never touch what prs-geom did not write
(:mod:`~prs_geom.exports.output`), mesh files (:mod:`~prs_geom.exports.meshes`), DXF
drawings (:mod:`~prs_geom.exports.dxf`), machining sheets (:mod:`~prs_geom.exports.sheets`),
plots (:mod:`~prs_geom.exports.plots`), the parts list (:mod:`~prs_geom.exports.bom`), the
glTF/3MF scenes with the mechanism's animation (:mod:`~prs_geom.exports.scene`), the HTML report (:mod:`~prs_geom.exports.html`, its
page templates in ``templates/``) and the JSON Schema of report.json
(:mod:`~prs_geom.exports.report_schema`). Exporters read the stage results; they compute
nothing of their own.
"""

__all__ = []
