"""Off-line task programs after WORKMATE (Smith 1986, seed 004, §III.D): tasks pasted from a menu
(FIND, PICKUP, PLACE, MOVE) with object-relative approach / grasp / depart motions, frames bound
at execution time by a simulated camera, every expanded motion verified (certified) before it is
emulated, and the program exported as Python that reproduces the same motions.

* :func:`load_program` / :func:`run_program` / :func:`export_program` — the task-program file
  (``armguard_program: 1``) and what is done with it;
* :class:`Cell` / :func:`load_cell` — the emulated cell: nominal model, real object poses, camera;
* :class:`Workcell` — the runtime primitives a program expands into;
* :func:`fit_rigid_transform` — robot–camera calibration's closed-form estimator (Horn / Umeyama)
  with its covariance; :func:`calibrate_camera` — the calibration program (a trained trajectory,
  FIND of the calibration object in the hand at each stop, the fit);
* :class:`Calibration` / :func:`read_calibration` / :func:`write_calibration` — calibration files
  (``armguard_calibration: 1``): the cell's relationships, nominal until a calibration updates them;
* :func:`weigh` / :func:`grasp_orientation` — the grasp error from a wrist force/torque sensor
  (§III.C): where the held object sits and how it is turned.

Guide: ``docs/program.md``.
"""

from ._calibrate import RigidFit, fit_rigid_transform
from ._calibfile import Calibration, calibration_text, read_calibration, write_calibration
from ._calibration import CalibrationStatus, CameraCalibration, calibrate_camera, calibration_poses, fit_camera
from ._grasp import GraspOrientation, Weighing, grasp_orientation, object_wrench, weigh
from ._cell import Camera, Cell, load_cell, object_frame
from ._program import Program, Step, export_program, load_program, program_text, run_program, workcell_main
from ._workcell import CONTACT_TOLERANCE, FindRecord, MotionRecord, ProgramRun, ProgramStopped, Workcell, pose

__all__ = [
    "Program",
    "Step",
    "load_program",
    "run_program",
    "export_program",
    "program_text",
    "workcell_main",
    "Cell",
    "Camera",
    "load_cell",
    "object_frame",
    "Workcell",
    "ProgramRun",
    "ProgramStopped",
    "MotionRecord",
    "FindRecord",
    "pose",
    "CONTACT_TOLERANCE",
    "fit_rigid_transform",
    "weigh",
    "Weighing",
    "grasp_orientation",
    "GraspOrientation",
    "object_wrench",
    "RigidFit",
    "Calibration",
    "read_calibration",
    "write_calibration",
    "calibration_text",
    "calibrate_camera",
    "calibration_poses",
    "fit_camera",
    "CameraCalibration",
    "CalibrationStatus",
]
