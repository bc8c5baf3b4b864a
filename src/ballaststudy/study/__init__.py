"""Study stage (thesis ch. 5): per-case metrics aggregated into `results/study.nc`, figures
like Figs. 5-1 ... 5-6, IRI tables (5.7) and the optimisation report (5.8)."""

from .aggregate import BEHAVIOURS, MEAN_SIZE_DEFINITION, aggregate, build_study, database_coordinates
from .iri import iri_table, write_iri
from .optimise import check_findings, database_summary, pareto_set, rank_databases, recommended
from .plots import write_figures
from .report import write_report

__all__ = ["BEHAVIOURS", "MEAN_SIZE_DEFINITION", "aggregate", "build_study", "database_coordinates",
           "iri_table", "write_iri", "check_findings", "database_summary", "pareto_set", "rank_databases",
           "recommended", "write_figures", "write_report"]
