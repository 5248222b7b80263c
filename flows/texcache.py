"""``make texcache``: the texel cache measured on the bump scenes.

Each bump scene of the gallery rendered through its RTL on the batch path, at 256 x 256 and
1024 x 1024, with a texture memory of 12 and of 40 clocks' latency, for several caches
(lines per bank, texels a line, ways; bilinear: a memory port per bank, or one shared): the hit
rate (look-ups that found their line), the
fragments per clock, and the memory words read per fragment. Writes
``build/texcache/texcache.{json,md}``; ``--quick``: the default cache only, latency 12.
"""
import argparse
import json
import sys

from sim.cli_common import user_errors
from sim.render import render
from sim.verilog import BUILD, SCENES

OUT = BUILD / "texcache"


def scene_names():
    """A scene of the gallery per bump method (its first by name): whatever reads texels."""
    from scene.parse import load
    out = {}
    for path in sorted(SCENES.glob("*.toml")):
        method = load(path).get("bump", {}).get("method", "none")
        if method != "none":
            out.setdefault(method, path.stem)
    return tuple(out.values())


# (cache_lines, cache_line, cache_ways, a port per bank)
CACHES = ((64, 1, 2, True), (256, 1, 4, True), (64, 4, 2, True), (64, 1, 2, False))
DEFAULT = CACHES[0]


def measure(scene, size, cache, latency):
    lines, line, ways, bank_ports = cache
    out = OUT / "render" / f"{scene}-{size}-{lines}x{line}x{ways}{'' if bank_ports else '-1p'}" \
        f"-l{latency}"
    m = render(SCENES / f"{scene}.toml", out, size=(size, size), quiet=True,
               hardware=dict(cache_lines=lines, cache_line=line, cache_ways=ways,
                             bank_ports=bank_ports), mem_latency=latency)
    n, reads = m["fragments"], m["memory"]["words_read"]
    banks = 4 if m["pipeline"]["params"]["filter"] == "bilinear" else 1
    return {"scene": scene, "size": size, "cache_lines": lines, "cache_line": line,
            "cache_ways": ways, "ports": banks if bank_ports else 1, "latency": latency,
            "fragments": n, "cycles": m["cycles"],
            "fragments_per_clock": m["fragments_per_clock"],
            "words_per_fragment": m["memory"]["words_per_fragment"],
            "hit_rate": round(1 - reads / line / (n * banks), 4),
            "filter": m["pipeline"]["params"]["filter"]}


def markdown(rows):
    head = ("| scene (filter) | screen | cache: lines x texels x ways | ports | latency | "
            "hit rate | fragments per clock | words per fragment |\n| --- | --- | --- | --- | "
            "--- | --- | --- | --- |")
    body = [f"| {r['scene']} ({r['filter']}) | {r['size']} | {r['cache_lines']} x "
            f"{r['cache_line']} x {r['cache_ways']} | {r['ports']} | {r['latency']} | "
            f"{r['hit_rate']:.3f} | {r['fragments_per_clock']:.3f} | "
            f"{r['words_per_fragment']:.3f} |" for r in rows]
    return "\n".join([head, *body])


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.texcache", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the default cache, latency 12")
    args = ap.parse_args(argv)
    from tqdm import tqdm
    todo = [(s, size, c, lat) for s in scene_names() for size in (256, 1024)
            for c in ((DEFAULT,) if args.quick else CACHES)
            for lat in ((12,) if args.quick else (12, 40))
            if c[3] or s == "bump_xz"]       # one port or four: bilinear's four banks only
    rows = []
    with user_errors():
        for job in tqdm(todo, desc="texcache", unit="render", file=sys.stderr):
            rows.append(measure(*job))
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "texcache.json").write_text(json.dumps(rows, indent=1) + "\n")
    md = markdown(rows)
    (OUT / "texcache.md").write_text(md + "\n")
    print(md)
    print(f"\nwrote {OUT / 'texcache.json'} and {OUT / 'texcache.md'}")


if __name__ == "__main__":
    main()
