"""Design-review report: PNG figures and one PDF from a case and its measured data.

matplotlib is imported only inside the functions of this package (``check`` never
loads it); import :func:`build_report` lazily from the CLI.
"""

from tuflexperf.report.build import PDF_NAME, ReportResult, build_report

__all__ = ["PDF_NAME", "ReportResult", "build_report"]
