"""Command line: ``warpbem demo`` runs the default scene, ``warpbem run`` / ``sweep`` run scene
files, ``warpbem plot`` charts a result, ``warpbem xdmf`` writes a run's moving meshes for ParaView,
``warpbem animate`` a GIF of a run.

A file that is missing, unreadable or not what the command needs, a scene that does not
validate and a --device this machine does not have end the command with one line on stderr
naming the file, field or device (exit status 2); a sweep point that fails, with one line naming
the point (exit status 1)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="warpbem", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="free cell passing an adherent cell: velocities and loads (HDF5 + PNG)")
    demo.add_argument("--output", default="results/demo.h5", help="HDF5 file to write (default %(default)s)")
    demo.add_argument("--device", default="cpu", help="Warp device, e.g. cpu or cuda:0 (default %(default)s)")
    demo.add_argument("--positions", type=int, default=25, help="streamwise positions (default %(default)s)")
    demo.add_argument("--no-plot", action="store_true", help="skip the PNG chart")
    run = sub.add_parser("run", help="time-step a scene file, writing HDF5 frames")
    run.add_argument("scene", nargs="?", help="scene file (TOML, see scenes/README.md)")
    run.add_argument("--output", required=True, help="HDF5 file of frames")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene value (on --resume only time.end and time.frame_every)")
    run.add_argument("--device", default="cpu")
    run.add_argument("--resume", action="store_true", help="continue the run in --output from its last frame")
    run.add_argument("--overwrite", action="store_true", help="replace an existing --output file")
    sweep = sub.add_parser("sweep", help="run a scene over a grid of values (one HDF5 per point, summary.csv);"
                                         " resumes a sweep already in --output-dir")
    sweep.add_argument("scene")
    sweep.add_argument("--vary", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="a scene key or a [sweep.AXIS] name of the scene, and its values (default: every"
                            " axis of the scene)")
    sweep.add_argument("--output-dir", required=True)
    sweep.add_argument("--overwrite", action="store_true", help="run every point afresh instead of resuming")
    where = sweep.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=1, help="local processes (default %(default)s)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the points on a Dask cluster, e.g. tcp://127.0.0.1:8786 (the dask extra; the"
                            " workers must see the scene and --output-dir at the same paths)")
    sweep.add_argument("--device", default="cpu")
    plot = sub.add_parser("plot", help="write the PNG chart of a run or demo HDF5 file")
    plot.add_argument("result", help="HDF5 file written by warpbem run or warpbem demo")
    plot.add_argument("--png", default=None, help="output PNG (default: beside the HDF5 file)")
    xdmf = sub.add_parser("xdmf", help="write RUN.xdmf (+ RUN.xdmf.h5) beside a run: its meshes moving, for ParaView")
    xdmf.add_argument("run", help="HDF5 file written by warpbem run or warpbem sweep (only read)")
    animate = sub.add_parser("animate", help="write an animated GIF of a run: side and top views to scale, bonds, time")
    animate.add_argument("run", help="HDF5 file written by warpbem run or warpbem sweep (only read)")
    animate.add_argument("--output", default=None, help="output GIF (default: beside the run file)")
    animate.add_argument("--frames", type=int, default=200, help="frames at most, spread evenly (default %(default)s)")
    animate.add_argument("--fps", type=float, default=10.0, help="GIF frames per second (default %(default)s)")
    return parser


def _demo(args, parser):
    from . import plotting
    from .demo import DemoScene, run

    if args.positions < 1:
        parser.error("--positions must be at least 1")
    output = Path(args.output)
    print(f"warpbem demo -> {output} (device {args.device})", flush=True)
    try:
        run(output, device=args.device, scene=DemoScene(positions=args.positions),
            progress=lambda line: print(line, flush=True))
    except KeyboardInterrupt:
        print(f"interrupted: the rows computed so far are in {output}", file=sys.stderr)
        return 130
    if not args.no_plot:
        print(f"chart: {plotting.plot_demo(output)}")
    return 0


def _run(args, parser):
    from .. import ConvergenceError, DeformationError
    from . import run as runner

    if not args.resume and not args.scene:
        parser.error("run needs a SCENE file (or --resume with --output)")
    try:
        runner.run(args.scene, args.output, args.set, args.device, args.resume,
                   progress=lambda line: print(line, flush=True), overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"interrupted: the frames so far are in {args.output}; continue with"
              f" warpbem run --resume --output {args.output}", file=sys.stderr)
        return 130
    except (DeformationError, ConvergenceError) as err:  # the scene left what its model can do
        print(f"warpbem run: stopped: {err}. The frames before it are in {args.output}", file=sys.stderr)
        return 1
    return 0


def _sweep(args, parser):
    from .sweep import sweep

    try:
        summary = sweep(args.scene, args.vary, args.output_dir, args.device, args.workers,
                        progress=lambda line: print(line, flush=True), scheduler=args.scheduler,
                        overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"interrupted: the points so far are in {args.output_dir}; the same command resumes the sweep",
              file=sys.stderr)
        return 130
    print(f"summary: {summary}")
    return 0


def _plot(args, parser):
    from . import plotting

    print(f"chart: {plotting.plot(args.result, args.png)}")
    return 0


def _xdmf(args, parser):
    from . import xdmf

    path = xdmf.write(args.run)
    print(f"xdmf: {path} (open it in ParaView; its data is in {path.with_suffix('.xdmf.h5').name})")
    return 0


def _animate(args, parser):
    from .animate import animate

    if args.frames < 1 or args.fps <= 0:
        parser.error("--frames must be at least 1 and --fps positive")
    print(f"gif: {animate(args.run, args.output, args.frames, args.fps)}")
    return 0


def _check_device(args) -> None:
    """The --device of a command that takes one, before any work: DeviceError naming the devices
    there are. A sweep on a Dask cluster runs on the workers' devices, not this machine's."""
    if getattr(args, "device", None) is not None and getattr(args, "scheduler", None) is None:
        from .. import runtime

        runtime.resolve_device(args.device)


VERBS = {"demo": _demo, "run": _run, "sweep": _sweep, "plot": _plot, "xdmf": _xdmf, "animate": _animate}


def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    from ..runtime import DeviceError
    from .io import RunFileError
    from .scene import SceneError
    from .sweep import SweepError

    try:
        _check_device(args)
        return VERBS[args.command](args, parser)
    except (SceneError, RunFileError, DeviceError) as err:
        print(f"warpbem {args.command}: {err}", file=sys.stderr)
        return 2
    except SweepError as err:
        print(f"warpbem {args.command}: {err}", file=sys.stderr)
        return 1
    except OSError as err:  # an output that cannot be written: the path and the reason
        print(f"warpbem {args.command}: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
