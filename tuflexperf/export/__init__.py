"""Model export for simulation and flight software: CasADi functions, C99 source, JSON (issue 6)."""

from tuflexperf.export.writer import FILES, FORMATS, ExportResult, export_model, parse_formats

__all__ = ["FILES", "FORMATS", "ExportResult", "export_model", "parse_formats"]
