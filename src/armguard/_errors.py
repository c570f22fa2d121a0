"""The armguard error hierarchy: one base class, one subclass per kind of failure."""

from __future__ import annotations

__all__ = [
    "ArmguardError",
    "GeometryError",
    "KinematicsError",
    "IKError",
    "JointLimitError",
    "SceneError",
    "SceneFileError",
    "TrajectoryError",
    "DetectionError",
    "VerificationError",
    "StaleModelError",
    "ClipError",
    "ForbiddenMapError",
    "ForbiddenMapFileError",
    "TerrainError",
    "TerrainFileError",
    "ReferenceFileError",
    "UncertaintyError",
    "ArmguardWarning",
    "OutputError",
    "AvoidanceError",
]


class ArmguardError(Exception):
    """Base class of every error armguard raises on purpose."""

    def __reduce__(self):
        # pickled as it stands (a Dask worker's error reaches the client): the subclasses' own __init__
        # signatures (JointLimitError's six arguments) cannot be called again with the message alone
        return _rebuilt, (type(self), self.args, self.__dict__)


def _rebuilt(cls, args, state):
    err = cls.__new__(cls)
    err.args = args
    err.__dict__.update(state)
    return err


class ArmguardWarning(UserWarning):
    """A lenient reading of an input armguard accepted (the message names the file and the element)."""


class GeometryError(ArmguardError, ValueError):
    """A shape or geometric query was given invalid data (NaN, negative radius, degenerate hull...)."""


class KinematicsError(ArmguardError, ValueError):
    """A kinematic model or a joint configuration is invalid (wrong length, outside limits, bad DH row)."""


class IKError(KinematicsError):
    """Inverse kinematics found no solution within tolerance and joint limits."""


class JointLimitError(KinematicsError):
    """A configuration puts a joint outside its [lower, upper] limits (beyond ``Tolerances.joint_limit``).

    Reach lists and lever-arm bounds hold only within the limits, so no verdict is given for such
    a configuration.  ``joint`` names the joint (``"robot/joint"``), ``value`` its value, ``lower``
    and ``upper`` its limits (rad or m), ``allowance`` the tolerance applied."""

    def __init__(self, where: str, joint: str, value: float, lower: float, upper: float, allowance: float) -> None:
        self.where, self.joint, self.value = where, joint, float(value)
        self.lower, self.upper, self.allowance = float(lower), float(upper), float(allowance)
        excess = self.value - self.upper if self.value > self.upper else self.lower - self.value
        side = "above the upper" if self.value > self.upper else "below the lower"
        digits = 9 if f"{self.value:.9g}" not in (f"{self.lower:.9g}", f"{self.upper:.9g}") else 17  # tell them apart
        f32 = (" (as small as float32's rounding: clip a float32 configuration to the limits, or give it as "
               "float64)" if excess <= 2.0 ** -23 * max(1.0, abs(self.value)) else "")
        super().__init__(
            f"{where}: joint {joint!r} = {self.value:.{digits}g} is outside its limits [{self.lower:.{digits}g}, "
            f"{self.upper:.{digits}g}]: {excess:.4g} {side}{f32} (allowance Tolerances.joint_limit = "
            f"{self.allowance:.3g}); no verdict is given outside the limits (the URDF's range of motion, within which "
            "the Detector's reach lists and motion bounds hold)"
        )


class SceneError(ArmguardError, ValueError):
    """A scene operation is invalid (unknown body, duplicate name, unknown robot)."""


class SceneFileError(SceneError):
    """A scene, robot or trajectory file could not be loaded; names the file, the place in it and what was expected."""

    def __init__(self, file: str, where: str, message: str, line: int | None = None) -> None:
        self.file = str(file)
        self.where = where
        self.message = message
        self.line = line  # 1-based line of ``where`` in the file, when known
        at = f" (line {line})" if line is not None and not where.startswith(f"line {line}") else ""
        loc = f"{self.file}: {where}{at}" if where else self.file
        super().__init__(f"{loc}: {message}")


def xml_parse_error(file, exc) -> SceneFileError:
    """The located error of ``file``, which ``xml.etree.ElementTree`` refused with ``exc`` (a ``ParseError``):
    ``line L, column C`` (1-based) and expat's reason, the place said once."""
    from xml.parsers import expat

    line, col = exc.position
    return SceneFileError(str(file), f"line {line}, column {col + 1}", f"not well-formed XML: {expat.ErrorString(exc.code)}"
                          + unclosed_text(file, exc.code), line=line)


def unclosed_text(file_or_bytes, code) -> str:
    """For expat's "mismatched tag" (reported at the closing tag that does not match): the element still open
    there and its line (an unclosed ``<parent>`` inside a ``<joint>``), as ``": <parent> opened at line 134 is not
    closed"``; else ``""``."""
    from xml.parsers import expat

    if code != expat.errors.codes.get(expat.errors.XML_ERROR_TAG_MISMATCH):
        return ""
    try:
        data = file_or_bytes if isinstance(file_or_bytes, bytes) else open(file_or_bytes, "rb").read()
    except OSError:
        return ""
    parser = expat.ParserCreate()
    stack: list = []
    parser.StartElementHandler = lambda tag, attrs: stack.append((tag, parser.CurrentLineNumber))
    parser.EndElementHandler = lambda tag: stack.pop()
    try:
        parser.Parse(data, True)
    except expat.ExpatError:
        if stack:
            tag, line = stack[-1]
            return f": <{tag}> opened at line {line} is not closed (or not written <{tag} .../>)"
    return ""


def list_problems(problems) -> tuple[str, str]:
    """``(where, message)`` of one error listing ``problems`` (``(where, message)`` pairs, at least
    one): the first problem's place, its message, then "N more problems:" and one line each."""
    where, first = problems[0]
    rest = "".join(f"\n  {w}: {m}" if w else f"\n  {m}" for w, m in problems[1:])
    n = len(problems) - 1
    return where, first + (f"\n{n} more problem{'s' if n > 1 else ''}:{rest}" if n else "")


class ToleranceError(ArmguardError, ValueError):
    """A :class:`armguard.Tolerances` field that is not a tolerance (NaN, infinite, zero or negative; a count
    below its least): refused when the Tolerances is made, before any verdict is computed with it."""


class TrajectoryError(ArmguardError, ValueError):
    """A trajectory is invalid (non-monotone times, wrong joint count, limits exceeded)."""


class DetectionError(ArmguardError, ValueError):
    """A detector was given an invalid query (bad configuration, unknown arm)."""


class VerificationError(ArmguardError, ValueError):
    """A trajectory verification request is invalid."""


class StaleModelError(VerificationError):
    """The scene changed (a body added, a pair disabled, ...) after a clearance model was built from it,
    or while it answered: its pairs are no longer the scene's, so it gives no answer.  ``Verifier`` and
    ``Guard`` catch it and build again from the scene as it is; code holding a
    :class:`armguard.verify.ClearanceModel` of its own builds a new one."""


class UncertaintyError(ArmguardError, ValueError):
    """An uncertain relation is invalid (non-finite mean, covariance not symmetric PSD, irreducible network...)."""


class TerrainError(ArmguardError, ValueError):
    """A terrain map, point file or terrain query is invalid (bad cell size, empty cloud, unsupported link volume...)."""


class TerrainFileError(TerrainError):
    """A terrain or point file could not be read: ``file``, ``where`` in it (an array, a header line) and ``message``."""

    def __init__(self, file, where: str, message: str) -> None:
        self.file, self.where, self.message = str(file), where, message
        super().__init__(_located(self.file, where, message))


class ReferenceFileError(ArmguardError, ValueError):
    """A golden reference file (``reference/models/<name>.json`` / ``.npz``) is missing, truncated, holds a
    non-finite value or fewer rows than its header says: ``file``, ``where`` (an array, a key) and ``message``."""

    def __init__(self, file, where: str, message: str) -> None:
        self.file, self.where, self.message = str(file), where, message
        super().__init__(_located(self.file, where, message))


class AvoidanceError(ArmguardError, ValueError):
    """Collision avoidance was given invalid settings, commands or distances (NaN, no Jacobian...)."""


class BackendError(ArmguardError, ValueError):
    """A backend is unknown, misconfigured, or was asked for something it does not answer."""


class ForbiddenMapError(ArmguardError, ValueError):
    """A forbidden-values map is invalid, was built for another model, or was asked outside its grid."""


def _located(file, where: str, message: str) -> str:
    return f"{file}: {where}: {message}" if where else f"{file}: {message}"


class ForbiddenMapFileError(ForbiddenMapError):
    """A map file (``.agmap``) or build journal (``.partial``) is damaged, truncated or of another format version;
    ``file`` names it, ``section`` the part that failed (``preamble``, ``header``, ``directory``, ``data``,
    ``substructure 17``, ``record 3``), ``message`` what was expected."""

    def __init__(self, file, section: str, message: str) -> None:
        self.file, self.section, self.message = str(file), section, message
        super().__init__(_located(self.file, section, message))


class ClipError(ArmguardError, ValueError):
    """A clipping guard, obstacle or prediction request is invalid (a shape without volume, a curved obstacle...)."""


class OutputError(ArmguardError, OSError):
    """An output file or folder could not be written (names the path and the reason); nothing half-written is left."""
