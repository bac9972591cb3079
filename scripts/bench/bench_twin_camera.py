"""The twin's webcam on this CPU: per frame, the MuJoCo render of the so101_blocks scene (arm, table, cubes, bins, the
board; the arm drawn as its view hulls), the lens, JPEG and publishing; then what LeRobot's `ZMQCamera` receives
while the server runs at 30 Hz.
Figures last: render_ms= lens_ms= jpeg_ms= publish_ms= frame_ms= max_fps= cpu_ms= received_fps=
(medians of wall time; cpu_ms is the CPU time one frame costs, the renderer's worker threads included: on a busy
machine wall times grow, CPU time much less.)

    .venv/bin/python scripts/bench/bench_twin_camera.py [--frames=150] [--seconds=5] [--port=5555]
"""

from __future__ import annotations

import argparse
import statistics
import threading
import time
from functools import partial

# The twin's camera first: it chooses MuJoCo's EGL backend before anything imports MuJoCo.
from lerobot_contrast.twin.camera import CameraArgs, TwinCamera, view_hulls  # isort: skip
from lerobot_contrast.twin.camera_server import encode, serve_camera
from lerobot_contrast.twin.lens import LensArgs


def world():
    import mujoco

    from lerobot_contrast.domains.task_file.loader import load_task_file
    from lerobot_contrast.so101.scene import build_spec
    from lerobot_contrast.twin.board import add_board

    task = load_task_file("so101_blocks").spec
    model = build_spec(task, extras=[view_hulls, partial(add_board, x=0.30, y=0.0, yaw_deg=10.0)]).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return task, model, data


def stages(camera: TwinCamera, model, data, frames: int) -> dict[str, float]:
    """Median milliseconds of each stage over `frames` frames, one after another on this thread."""
    times: dict[str, list[float]] = {"render": [], "lens": [], "jpeg": []}
    camera.frame(model, data)  # the renderer's context and the model's upload, once
    cpu = time.process_time()
    for _ in range(frames):
        started = time.perf_counter()
        camera.capture(model, data)
        canvas = camera._renderer.render()
        rendered = time.perf_counter()
        frame = camera.lens.apply(canvas)
        lensed = time.perf_counter()
        encode("front", frame, time.time())
        encoded = time.perf_counter()
        times["render"].append(rendered - started)
        times["lens"].append(lensed - rendered)
        times["jpeg"].append(encoded - lensed)
    cpu_ms = 1000 * (time.process_time() - cpu) / frames
    return {name: 1000 * statistics.median(values) for name, values in times.items()} | {"cpu": cpu_ms}


def received_fps(model, data, target, port: int, seconds: float) -> tuple[float, float]:
    """Frames per second LeRobot's ZMQCamera receives from the server at 30 Hz, and the server's publish ms."""
    from lerobot.cameras.zmq import ZMQCamera, ZMQCameraConfig

    lock = threading.Lock()

    def read(view):
        with lock:
            return view(model, data)

    server = serve_camera(read, target, CameraArgs(), LensArgs(), port=port, fps=30)
    reader = ZMQCamera(ZMQCameraConfig(server_address="127.0.0.1", port=port, camera_name="front"))
    try:
        reader.connect()
        count, started = 0, time.perf_counter()
        while time.perf_counter() - started < seconds:
            reader.async_read(timeout_ms=1000)
            count += 1
        elapsed = time.perf_counter() - started
    finally:
        reader.disconnect()
        server.stop()
    if server.error:
        raise SystemExit(server.error)
    return count / elapsed, 1000 * server.times.send_s / max(server.times.frames, 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--port", type=int, default=5555)
    args = parser.parse_args()
    task, model, data = world()
    target = (*task.workspace.area.middle, 0.0)  # the camera looks at the workspace's centre on the table
    print(f"scene: {task.name}, {model.ngeom} geoms, the camera looking at {target}")
    camera = TwinCamera(target, CameraArgs(), LensArgs())
    try:
        ms = stages(camera, model, data, args.frames)
    finally:
        camera.close()
    fps, publish_ms = received_fps(model, data, target, args.port, args.seconds)
    frame_ms = ms["render"] + ms["lens"] + ms["jpeg"] + publish_ms
    print(f"canvas {camera.lens.canvas_size[0]}x{camera.lens.canvas_size[1]} -> frame 640x480, {args.frames} frames")
    print(" ".join([f"render_ms={ms['render']:.1f}", f"lens_ms={ms['lens']:.1f}", f"jpeg_ms={ms['jpeg']:.1f}",
                    f"publish_ms={publish_ms:.2f}", f"frame_ms={frame_ms:.1f}", f"max_fps={1000 / frame_ms:.0f}",
                    f"cpu_ms={ms['cpu']:.1f}", f"received_fps={fps:.1f}"]))  # fmt: skip


if __name__ == "__main__":
    main()
