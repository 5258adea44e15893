"""The 3-D view (``synth view``): one offline HTML page of the workcell, the arm and its run.

**Library: three.js**, vendored in ``synth/data/`` (r160, MIT) and inlined into the page. It is
the smallest thing that draws lit triangle meshes in any browser with no server and no network:
one 670 kB file, no build step. Pinocchio's visualiser back-ends (MeshCat, Viser) serve the
scene from a running Python process (a static export still fetches their viewer's bundle), and
they would animate from their own copy of the kinematics; here every pose comes from the replay.

**What the page holds** (:func:`view_scene`, a JSON document; :func:`view_html` the page):

* every solid as triangles (float32 positions, uint32 indices, base64): the table and the boxes
  with their holes as the replay's Coal geometry has them, the pins' meshes, and the arm's
  collision bodies (its links and the hand, the fingers at the sampled opening);
* each moving body's world pose at every sample of a :class:`~synth.replay.trace.Trace`
  (``x, y, z, qx, qy, qz, qw``, float32): arm bodies by forward kinematics of the trace's
  joints, pins from the trace's own poses; static bodies one pose;
* the samples' times [s] and AL lines, and the program text: the page highlights the line of
  the motion playing. ``?t=SECONDS`` in the URL freezes the animation at that time;
* the camera (eye, target, vertical field of view [deg]) and the canvas size [px], chosen here
  so that a test can project a world point to its pixel (:func:`project`).
"""

from __future__ import annotations

import base64
import json
import math
import re
from dataclasses import dataclass
from importlib import resources
from typing import Any

import coal
import numpy as np
import pinocchio as pin
import trimesh
from numpy.typing import NDArray

from synth.exceptions import SynthError
from synth.models.arm.bodies import Body
from synth.models.arm.collision import body_at_opening
from synth.replay.run import ReplayContext
from synth.replay.trace import Trace
from synth.replay.truth import nominal_world

__all__ = ["Camera", "project", "triangles", "view_html", "view_scene"]

CANVAS = (960, 720)
"""[px] the 3-D canvas (width, height); the program panel stands to its right."""
PANEL = 360
"""[px] width of the program panel."""
BACKGROUND = "#f4f4f4"
COLOURS = {
    "table": "#b9b9b9",
    "object": "#c8a165",
    "pin": "#d8b400",
    "arm": "#2f62d0",
    "hand": "#1d2f66",
}


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: ``eye`` and ``target`` [m], vertical ``fov`` [deg], world z up."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    fov: float
    near: float
    far: float

    def to_json(self) -> dict[str, Any]:
        """``{"eye", "target", "fov", "near", "far"}``."""
        return {
            "eye": list(self.eye),
            "target": list(self.target),
            "fov": self.fov,
            "near": self.near,
            "far": self.far,
        }


def project(
    camera: Camera, point: NDArray[np.float64], size: tuple[int, int] = CANVAS
) -> tuple[float, float]:
    """Pixel ``(column, row)`` of world ``point`` [m] (three.js's perspective, z up)."""
    eye, target = np.array(camera.eye), np.array(camera.target)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = np.asarray(point, dtype=float) - eye
    depth = float(forward @ d)
    tan = math.tan(math.radians(camera.fov) / 2)
    width, height = size
    x = float(right @ d) / (depth * tan * width / height)
    y = float(up @ d) / (depth * tan)
    return (x + 1) / 2 * width, (1 - y) / 2 * height


def triangles(geometry: Any) -> tuple[NDArray[np.float32], NDArray[np.uint32]]:
    """Vertices (N, 3) [m] and triangles (M, 3) of a Coal shape or mesh, or a trimesh mesh."""
    if isinstance(geometry, trimesh.Trimesh):
        mesh = geometry
    elif isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=np.float32).reshape(-1, 3)
        faces = []
        for i in range(geometry.num_tris):
            t = geometry.tri_indices(i)
            faces.append((t[0], t[1], t[2]))
        return vertices, np.asarray(faces, dtype=np.uint32).reshape(-1, 3)
    elif isinstance(geometry, coal.Box):
        mesh = trimesh.creation.box(extents=2 * np.asarray(geometry.halfSide))
    elif isinstance(geometry, coal.Cylinder):
        mesh = trimesh.creation.cylinder(geometry.radius, 2 * geometry.halfLength, sections=24)
    elif isinstance(geometry, coal.Capsule):
        mesh = trimesh.creation.capsule(2 * geometry.halfLength, geometry.radius)
    elif isinstance(geometry, coal.Sphere):
        mesh = trimesh.creation.icosphere(2, geometry.radius)
    else:
        raise ValueError(f"cannot draw a {type(geometry).__name__}")
    return (
        np.asarray(mesh.vertices, dtype=np.float32),
        np.asarray(mesh.faces, dtype=np.uint32),
    )


def _b64(array: NDArray[Any]) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def _pose7(pose: pin.SE3) -> list[float]:
    q = pin.Quaternion(pose.rotation)
    return [*(float(v) for v in pose.translation), float(q.x), float(q.y), float(q.z), float(q.w)]


def _solid(name: str, role: str, geometry: Any) -> dict[str, Any]:
    vertices, faces = triangles(geometry)
    return {
        "name": name,
        "role": role,
        "color": COLOURS[role],
        "positions": _b64(vertices),
        "indices": _b64(faces),
    }


def _camera(points: NDArray[np.float64], base: NDArray[np.float64]) -> Camera:
    """Look at the middle of ``points`` [m] from beyond them, the arm's ``base`` behind.

    The eye stands on the far side of the workcell from the base, turned 35° about z and
    raised 35°, at the distance where a ball of the points' half-diagonal (× 1.5) fills the
    vertical field of view.
    """
    lo, hi = points.min(axis=0), points.max(axis=0)
    target = (lo + hi) / 2
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 0.1)
    fov = 40.0
    distance = 1.5 * radius / math.sin(math.radians(fov) / 2)
    away = target[:2] - base[:2]
    heading = math.atan2(away[1], away[0]) if np.linalg.norm(away) > 1e-6 else -math.pi / 2
    heading += math.radians(35.0)
    up = math.radians(35.0)
    direction = np.array(
        [math.cos(up) * math.cos(heading), math.cos(up) * math.sin(heading), math.sin(up)]
    )
    eye = target + distance * direction
    return Camera(
        (float(eye[0]), float(eye[1]), float(eye[2])),
        (float(target[0]), float(target[1]), float(target[2])),
        fov,
        distance / 50,
        distance * 10,
    )


def arm_body_poses(
    context: ReplayContext, q: NDArray[np.float64], opening: float
) -> list[tuple[Body, pin.SE3]]:
    """Each arm body (fingers at ``opening`` [m]) with its world pose at joints ``q``."""
    arm = context.arm
    data = arm.model.createData()
    pin.forwardKinematics(arm.model, data, np.asarray(q, dtype=float))
    out = []
    for body in arm.bodies:
        placed = body_at_opening(arm, body, opening)
        out.append((placed, data.oMi[placed.joint] * placed.placement))
    return out


def view_scene(context: ReplayContext, trace: Trace, program_text: str) -> dict[str, Any]:
    """The page's JSON document (module docstring) from a replay context and its trace."""
    if not trace.samples:
        report = trace.report
        ended = f"{report.outcome} at line {report.line}" if report.line else report.outcome
        raise SynthError(
            f"the program ends ({ended}: {report.message}) before it makes a motion: "
            "there is nothing to view"
        )
    workcell = context.workcell.place(nominal_world(context.graph))
    bodies: list[dict[str, Any]] = []
    static_points = []
    for obstacle in workcell.obstacles:
        role = "table" if obstacle.name == context.workcell.table.name else "object"
        solid = _solid(obstacle.name, role, obstacle.geometry)
        solid["pose"] = _pose7(obstacle.pose)
        solid["poses"] = None
        bodies.append(solid)
        if role == "object":
            static_points.append(obstacle.pose.translation)
    al_of_frame = {model.name: model.frame for model in workcell.pins.values()}
    for name in trace.samples[0].pins:
        frame = al_of_frame.get(name)
        if frame is None:
            continue
        solid = _solid(name, "pin", workcell.pins[frame].mesh)
        poses = np.array([_pose7(s.pins[name]) for s in trace.samples], dtype=np.float32)
        solid["pose"], solid["poses"] = None, _b64(poses)
        bodies.append(solid)
        static_points.append(trace.samples[0].pins[name].translation)
    per_sample = [arm_body_poses(context, np.array(s.q), s.opening) for s in trace.samples]
    for k, body in enumerate(context.arm.bodies):
        role = "hand" if body.role == "hand" else "arm"
        solid = _solid(body.name, role, body.geometry)
        poses = np.array([_pose7(sample[k][1]) for sample in per_sample], dtype=np.float32)
        solid["pose"], solid["poses"] = None, _b64(poses)
        bodies.append(solid)
    hands = np.array([s.hand.translation for s in trace.samples])
    base = context.arm.world_from_base.translation
    camera = _camera(np.vstack([*static_points, hands]), base)
    width, height = CANVAS
    return {
        "title": f"{trace.program} on {trace.task}",
        "background": BACKGROUND,
        "canvas": {"width": width, "height": height, "panel": PANEL},
        "camera": camera.to_json(),
        "program": program_text.splitlines(),
        "times": [s.t for s in trace.samples],
        "lines": [s.line for s in trace.samples],
        "motions": [s.motion for s in trace.samples],
        "bodies": bodies,
    }


_EXPORTS = re.compile(r"export\s*\{([^}]*)\}\s*;?\s*$")


def _classic_three() -> tuple[str, str]:
    """three.js's module source without its final ``export {…}``, and that list as an object.

    The page runs it as a classic script inside a function, so it needs no module loader and
    runs before the page's own script, also from a ``file://`` URL.
    """
    source = (resources.files("synth") / "data" / "three.module.min.js").read_text("utf-8")
    match = _EXPORTS.search(source)
    if match is None:
        raise ValueError("three.module.min.js: no final export list")
    pairs = []
    for item in match.group(1).split(","):
        local, _, exported = item.strip().partition(" as ")
        pairs.append(f"{(exported or local).strip()}:{local.strip()}")
    return source[: match.start()], "{" + ",".join(pairs) + "}"


def script_json(value: Any) -> str:
    r"""``value`` as JSON safe inside an HTML ``<script>`` element.

    ``<``, ``>`` and ``&`` are written as JSON's ``\u003c``, ``\u003e``, ``\u0026`` (the same
    string to a JSON parser), so no text from a task can close the element (``</script>``) or
    switch the HTML parser into a script's escaped state (``<!--``, which took the rest of the
    page with it: a task named ``<!--<script>`` left the program panel empty).
    """
    text = json.dumps(value, separators=(",", ":"))
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def view_html(scene: dict[str, Any]) -> str:
    """The self-contained page for a :func:`view_scene` document."""
    template = (resources.files("synth") / "data" / "view.html").read_text("utf-8")
    three, exports = _classic_three()
    payload = script_json(scene)
    title = str(scene["title"]).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    values = {"TITLE": title, "SCENE": payload, "THREE": three, "THREE_EXPORTS": exports}
    return re.sub(r"@@([A-Z_]+)@@", lambda m: values[m.group(1)], template)
