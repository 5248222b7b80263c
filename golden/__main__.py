"""``python -m golden run UNIT --in IN.npz --out OUT.npz [--param NAME=VALUE ...]``

Streams every row of IN through the unit's golden model and writes raw integers (float
models are rounded to the nearest raw step and saturated to the field)."""
import argparse

from hdl.units import UNITS, make_unit, parse_params
from sim.cli_common import (check_output_path, read_inputs, rows, summary, user_errors,
                            write_outputs)

from . import MODELS, raster


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m golden", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser("run", help="run a unit's golden model on an npz of raw inputs")
    run.add_argument("unit", choices=sorted(UNITS))
    run.add_argument("--in", dest="inp", required=True)
    run.add_argument("--out", required=True)
    run.add_argument("--param", action="append", default=[], metavar="NAME=VALUE")
    args = ap.parse_args(argv)
    with user_errors():
        params = parse_params(args.unit, args.param)
        unit = make_unit(args.unit, spec=True, **params)
        inputs = read_inputs(unit, args.inp)
        check_output_path(args.out)
        out = MODELS[args.unit].run(inputs, **unit.params) if rows(inputs) else \
            {f.name: [] for f in unit.outputs}
        write_outputs(unit, args.out, out)
        culled = raster.culled(inputs) if unit.status_ports else None
        print(f"{args.unit} (golden model): {summary(unit, inputs, out, culled)} -> {args.out}")


if __name__ == "__main__":
    main()
