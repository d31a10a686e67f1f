"""Self-contained HTML reports: sections, tables, figures, parameters with
uncertainty and pass / fail against a datasheet-style specification."""

from imunav.lab.report.html import Parameter, Report, Section
from imunav.lab.report.spec import SpecCheck, SpecLimit, check_spec, load_spec

__all__ = ["Report", "Section", "Parameter", "SpecLimit", "SpecCheck", "check_spec", "load_spec"]
