"""Confine a task's file references (arm URDF, SRDF, package directories) to model directories.

A task sent to the server must not make it read arbitrary files. Every reference is resolved
against the configured model directories only: relative paths may not contain ``..``; an
absolute path must already lie inside one of them; the resolved path (symlinks followed) must
still lie inside the directory it was found in and must exist. The spec handed to synth then
carries absolute, checked paths, so the library's own resolution (relative to a base directory)
leaves them unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path, PurePosixPath, PureWindowsPath

from synth.exceptions import SpecError
from synth.models.spec import TaskSpec


def _inside(path: Path, root: Path) -> bool:
    return path == root or root in path.parents


def resolve_model_file(
    reference: str, field: str, model_dirs: Sequence[Path], *, directory: bool = False
) -> Path:
    """The checked absolute path of ``reference`` (a spec field's value) in ``model_dirs``.

    ``field`` is the spec path reported in errors (``manipulator.arm.urdf``). Raises
    :class:`SpecError` when the server has no model directories, the reference escapes them
    (``..``, an absolute path elsewhere, a symlink pointing out) or names nothing there.
    """
    if not model_dirs:
        raise SpecError(
            field,
            "this server reads no model files (no model directories configured); "
            "use 'model: stanford' or ask the operator to set SYNTH_MODEL_DIRS",
        )
    if not reference or "\x00" in reference:
        raise SpecError(field, "not a valid path")
    parts = PurePosixPath(reference).parts + PureWindowsPath(reference).parts
    if ".." in parts:
        raise SpecError(field, "'..' is not allowed in model paths")
    roots = [d.resolve() for d in model_dirs]
    candidate = Path(reference)
    if candidate.is_absolute():
        lexical = Path(*candidate.parts)
        owners = [r for r in roots if _inside(lexical, r)]
        if not owners:
            raise SpecError(field, "absolute paths must lie inside a model directory")
        tries = [(owners[0], lexical)]
    else:
        tries = [(r, r / candidate) for r in roots]
    for root, path in tries:
        try:
            resolved = path.resolve(strict=True)
        except (OSError, RuntimeError):
            continue
        if not _inside(resolved, root):
            raise SpecError(field, "the path leaves the model directory (symlink)")
        if directory and not resolved.is_dir():
            raise SpecError(field, "not a directory")
        if not directory and not resolved.is_file():
            raise SpecError(field, "not a file")
        return resolved
    raise SpecError(field, f"{reference!r} is not in the server's model directories")


def confine_model_files(spec: TaskSpec, model_dirs: Sequence[Path]) -> TaskSpec:
    """``spec`` with its URDF, SRDF and package paths replaced by checked absolute paths.

    A refusal carries the field's line in the posted YAML, as every other spec refusal does
    (it had ``"line": null``, the fourth hunt).
    """
    with spec.lines_on_errors():
        return _confined(spec, model_dirs)


def _confined(spec: TaskSpec, model_dirs: Sequence[Path]) -> TaskSpec:
    if spec.manipulator is None:
        return spec
    arm = spec.manipulator.arm
    if arm.urdf is None and arm.srdf is None and not arm.package_dirs:
        return spec
    base = "manipulator.arm"
    changes: dict[str, object] = {}
    if arm.urdf is not None:
        changes["urdf"] = str(resolve_model_file(arm.urdf, f"{base}.urdf", model_dirs))
    if arm.srdf is not None:
        changes["srdf"] = str(resolve_model_file(arm.srdf, f"{base}.srdf", model_dirs))
    if arm.package_dirs:
        changes["package_dirs"] = tuple(
            str(resolve_model_file(d, f"{base}.package_dirs[{i}]", model_dirs, directory=True))
            for i, d in enumerate(arm.package_dirs)
        )
    new_arm = arm.model_copy(update=changes)
    manipulator = spec.manipulator.model_copy(update={"arm": new_arm})
    return spec.model_copy(update={"manipulator": manipulator})


__all__ = ["confine_model_files", "resolve_model_file"]
