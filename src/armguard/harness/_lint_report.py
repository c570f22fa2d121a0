"""The findings of :func:`armguard.harness.check_model_files` (``armguard check-urdf``): what each
check is called, how severe a finding is, and the report."""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass, field

__all__ = ["Check", "Severity", "LintStatus", "Finding", "LintReport"]


class Check(str, enum.Enum):
    LOAD = "load"
    UNPARSED = "unparsed"
    NON_CONVEX = "non-convex"
    ZERO_LENGTH_CAPSULE = "zero-length-capsule"
    SRDF_NAME = "srdf-name"
    PERMANENT_COLLISION = "permanent-collision"
    HOME_COLLISION = "home-collision"
    SRDF_CERTIFICATE = "srdf-certificate"
    FROZEN_JOINT = "frozen-joint"
    UNREAD_ELEMENT = "unread-element"
    MIMIC_RANGE = "mimic-range"
    UNITS = "units"


class Severity(str, enum.Enum):
    ERROR = "error"
    WARNING = "warning"


class LintStatus(str, enum.Enum):
    CLEAN = "clean"
    WARNINGS = "warnings"
    ERRORS = "errors"


@dataclass(frozen=True)
class Finding:
    check: Check
    severity: Severity
    where: str  # file and element, e.g. "hermes.urdf: link[hera_link3].collision[0]"
    message: str
    suggestion: str | None = None


@dataclass
class LintReport:
    target: str
    urdf: str | None
    srdf: str | None
    findings: list = field(default_factory=list)
    summary: str = ""

    @property
    def status(self) -> LintStatus:
        if any(f.severity is Severity.ERROR for f in self.findings):
            return LintStatus.ERRORS
        return LintStatus.WARNINGS if self.findings else LintStatus.CLEAN

    def by_check(self, check: Check) -> list:
        return [f for f in self.findings if f.check is Check(check)]

    def to_dict(self) -> dict:
        return {"target": self.target, "urdf": self.urdf, "srdf": self.srdf, "status": self.status.value,
                "summary": self.summary,
                "findings": [{**asdict(f), "check": f.check.value, "severity": f.severity.value} for f in self.findings]}
