"""``python -m board``: the ULX3S (docs/board.md).

    python -m board sim SCENE.toml --out DIR [--size WxH]        the core on Verilator, one frame
    python -m board build SCENE.toml --board ulx3s-25f --out DIR  the bitstream
    python -m board send SCENE.toml --port /dev/ttyUSB0           a scene to the board
    python -m board program DIR/<name>.bit                        openFPGALoader, where installed
"""
import argparse
import json
import sys

__all__ = ["main"]

BOARDS = ("ulx3s-25f", "ulx3s-85f")


class UsageError(Exception):
    pass


def _size(text):
    if not text:
        return None
    w, sep, h = text.lower().partition("x")
    if not (sep and w.isdigit() and h.isdigit()):
        raise UsageError(f"--size must be WIDTHxHEIGHT, not {text!r}")
    return int(w), int(h)


def _sim(args):
    from .sim import run
    r = run(args.scene, args.out, _size(args.size), args.board)
    print(json.dumps({k: r[k] for k in ("scene", "size", "clocks_to_render", "link_bytes",
                                        "pixels_differ")}))
    print(f"wrote {args.out}/tmds.npy, frame.png, model.png, board.json")
    return 0 if r["pixels_differ"] == 0 and not r["symbol_errors"] else 1


def _build(args):
    from .build import build
    r = build(args.scene, args.out, args.board, _size(args.size), seed=args.seed)
    print(json.dumps(r, indent=1))
    return 0 if all(c["achieved_mhz"] >= c["constraint_mhz"]
                    for c in r["clocks"].values()) else 1


def _send(args):
    from .send import send
    send(args.scene, args.port, _size(args.size), args.board)
    return 0


def _program(args):
    from .build import program
    program(args.bitstream)
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m board", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    for name, fn in (("sim", _sim), ("build", _build), ("send", _send)):
        p = sub.add_parser(name)
        p.add_argument("scene", metavar="SCENE.toml")
        p.add_argument("--size", metavar="WxH", help="override the scene's image size")
        p.add_argument("--board", choices=BOARDS, default="ulx3s-25f")
        if name == "send":
            p.add_argument("--port", required=True, help="the FT231X's serial port")
        else:
            p.add_argument("--out", required=True, metavar="DIR")
        if name == "build":
            p.add_argument("--seed", type=int, default=1, help="nextpnr's placer seed")
        p.set_defaults(fn=fn)
    p = sub.add_parser("program")
    p.add_argument("bitstream", metavar="DIR/NAME.bit")
    p.set_defaults(fn=_program)
    args = ap.parse_args(argv)
    from scene.driver import SceneError
    try:
        return args.fn(args)
    except (UsageError, SceneError, ValueError, OSError) as e:
        print(f"python -m board {args.cmd}: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
