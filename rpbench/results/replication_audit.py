"""The replication folder audit, under the name ``rpbench replicate`` imports it by: it is
:mod:`rpbench.results.check.replication`, one of the checker's modules."""

from rpbench.results.check.replication import (
    RECORDS_DIR,
    ROUND_S,
    SKIPPED,
    TOL_M,
    audit_folder,
    audit_run,
    records_file,
)

__all__ = ["RECORDS_DIR", "ROUND_S", "SKIPPED", "TOL_M", "audit_folder", "audit_run", "records_file"]
