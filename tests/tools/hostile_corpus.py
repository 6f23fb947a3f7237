#!/usr/bin/env python3
"""The hostile-input corpus (issue 20), run as a user runs the command line.

Each case is a command with its expected exit code, a fragment its stderr must hold (the file and
JSON pointer, or the option, it blames) and the files that must, or must not, exist afterwards
(a temporary file `*.tmp-*` never may). Every case runs in its own empty directory, so a case
cannot pass on another's leftovers.

Usage: hostile_corpus.py PALPABLE SOURCE_DIR [-k SUBSTRING]
"""
import copy
import glob
import json
import os
import stat
import subprocess
import sys
import tempfile
import time

palpable, source = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
only = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "-k" else None
scenes = os.path.join(source, "scenarios")
corpus = json.load(open(os.path.join(source, "tests", "scenarios", "bad_scenes.json")))
BASE = corpus["base"]

cases = []


def case(name, args, code, fragment=None, files=None, exists=(), absent=(), stdin=None,
         check=None, timeout=60, links=None):
    """files: {name: bytes | str | dict (JSON)} written before the run; links: {name: target}
    symlinks made before it; check: a function of the directory returning an error string or
    None, for promises a file list cannot say."""
    cases.append(dict(name=name, args=args, code=code, fragment=fragment, files=files or {},
                      exists=exists, absent=absent, stdin=stdin, check=check, timeout=timeout,
                      links=links or {}))


def scene(**changes):
    """The corpus's base scene with top-level keys replaced (None removes)."""
    doc = copy.deepcopy(BASE)
    for k, v in changes.items():
        if v is None:
            doc.pop(k, None)
        else:
            doc[k] = v
    return doc


def with_settings(**settings):
    doc = scene()
    doc["settings"].update(settings)
    return doc


def with_body(index, **changes):
    doc = scene()
    doc["bodies"][index].update(changes)
    return doc


def apply_patch(doc, patch):
    """The RFC 6902 subset bad_scenes.json uses: add, replace, remove."""
    doc = copy.deepcopy(doc)
    for op in patch:
        parts = [p.replace("~1", "/").replace("~0", "~") for p in op["path"].split("/")[1:]]
        parent = doc
        for p in parts[:-1]:
            parent = parent[int(p)] if isinstance(parent, list) else parent[p]
        last = parts[-1]
        if isinstance(parent, list):
            if op["op"] == "remove":
                del parent[int(last)]
            elif op["op"] == "add":
                if last == "-":
                    parent.append(op["value"])
                else:
                    parent.insert(int(last), op["value"])
            else:
                parent[int(last)] = op["value"]
        else:
            if op["op"] == "remove":
                del parent[last]
            else:
                parent[last] = op["value"]
    return doc


# --- 1. Every bad scene of the corpus, through `run`, with a trace asked for: exit 2 naming the
# file and pointer, no trace, no temporary.
for c in corpus["cases"]:
    case("bad scene: " + c["what"], ["run", "s.json", "--trace", "t.csv"], 2,
         "s.json:" + c["path"], files={"s.json": apply_patch(BASE, c["patch"])},
         absent=["t.csv", "t.csv.json"])

# --- 2. Hostile JSON text.
deep = "[" * 100000 + "]" * 100000
case("JSON 100,000 deep in description", ["run", "s.json"], 2, "nested deeper than 256",
     files={"s.json": json.dumps(scene())[:-1] + ', "description": ' + deep + "}"})
case("JSON 100,000 deep in reference", ["run", "s.json"], 2, "nested deeper than 256",
     files={"s.json": json.dumps(scene())[:-1] + ', "reference": ' + deep + "}"})
case("JSON 100,000 deep as the whole scene", ["run", "s.json"], 2, "s.json: nested deeper",
     files={"s.json": deep})
case("end_time 1e999 in the file", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene()).replace('"end_time": 1.0', '"end_time": 1e999')})
case("a mass of -1e999", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene()).replace('"mass": 1.0', '"mass": -1e999')})
case("an integer past 2^64", ["run", "s.json"], 2, "s.json:/settings/retry_limit",
     files={"s.json": json.dumps(scene())[:-1].replace(
         '"settings": {', '"settings": {"retry_limit": 123456789012345678901234567890, ') + "}"})
case("a string that is not UTF-8 in the file", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene(name="x")).replace('"name": "x"', '"name": "\xff"')
            .encode("latin-1")})
case("a UTF-16 file", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene()).encode("utf-16")})
case("an empty file", ["run", "s.json"], 2, "s.json", files={"s.json": b""})
case("binary garbage", ["run", "s.json"], 2, "s.json", files={"s.json": bytes(range(256)) * 8})
case("NaN in the file", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene()).replace('"end_time": 1.0', '"end_time": NaN')})
case("a trailing comma", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene())[:-1] + ",}"})
case("two documents", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(scene()) + json.dumps(scene())})
case("a JSON array as the scene", ["run", "s.json"], 2, "s.json", files={"s.json": "[1, 2]"})
case("a scene that does not exist", ["run", "nothing.json"], 2, "nothing.json")
case("a directory as the scene", ["run", "."], 2, ".: is a directory")
case("a scene on standard input that is not JSON", ["run", "-"], 2, "-", stdin=b"not json")
case("duplicate keys: the last wins, still validated", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": json.dumps(scene())[:-1] + ', "end_time": -1}'})

# --- 3. Parameters and =expressions.
case("an =expression 100,000 deep", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": scene(end_time="=" + "(" * 100000 + "1" + ")" * 100000)})
case("an =expression of 100,000 signs", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": scene(end_time="=" + "-" * 100000 + "1")})
case("an =expression dividing by zero", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": scene(end_time="=1/0")})
case("an =expression with 1e999", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": scene(end_time="=1e999")})
case("an =expression naming nothing", ["run", "s.json"], 2, "s.json:/end_time",
     files={"s.json": scene(end_time="=x + 1")})
case("a parameter that is not finite", ["run", "s.json"], 2, "s.json:/parameters/a",
     files={"s.json": scene(parameters={"a": "=exp(1000)"}, end_time="=a")})
case("a parameter named pi", ["run", "s.json"], 2, "s.json:/parameters/pi",
     files={"s.json": scene(parameters={"pi": 3})})
case("parameters not an object", ["run", "s.json"], 2, "s.json:/parameters",
     files={"s.json": scene(parameters=[1])})

# --- 4. Ranges checked before the run.
case("end_time 1e300", ["run", "s.json"], 2, "s.json:/end_time", files={"s.json": scene(end_time=1e300)})
case("envelope 1e-300", ["run", "s.json"], 2, "s.json:/settings/envelope",
     files={"s.json": with_settings(envelope=1e-300)})
case("envelope 1e-300 with --strict", ["run", "s.json", "--strict"], 2, "s.json:/settings/envelope",
     files={"s.json": with_settings(envelope=1e-300)})
case("envelope 1e3", ["run", "s.json"], 2, "s.json:/settings/envelope",
     files={"s.json": with_settings(envelope=1e3)})
case("broad_phase_horizon 1e-300", ["run", "s.json"], 2, "s.json:/settings/broad_phase_horizon",
     files={"s.json": with_settings(broad_phase_horizon=1e-300)})
case("microcollision_speed 1e300", ["run", "s.json"], 2, "s.json:/settings/microcollision_speed",
     files={"s.json": with_settings(microcollision_speed=1e300)})
case("gravity 1e300", ["run", "s.json"], 2, "s.json:/gravity",
     files={"s.json": scene(gravity=[0, 0, -1e300])})
case("output interval 1e-12", ["run", "s.json", "--trace", "t.csv"], 2, "s.json:/output/interval",
     files={"s.json": scene(output={"interval": 1e-12})}, absent=["t.csv"])
case("a sphere of radius 1e-200", ["run", "s.json"], 2, "s.json:/bodies/1/shape/radius",
     files={"s.json": with_body(1, shape={"type": "sphere", "radius": 1e-200})})
case("a sphere of radius 1e200", ["run", "s.json"], 2, "s.json:/bodies/1/shape/radius",
     files={"s.json": with_body(1, shape={"type": "sphere", "radius": 1e200})})
case("a box 2e-200 m thick", ["run", "s.json"], 2, "s.json:/bodies/2/shape/half_extents/2",
     files={"s.json": with_body(2, shape={"type": "box", "half_extents": [0.1, 0.1, 1e-200]})})
case("a mass of 1e-300", ["run", "s.json"], 2, "s.json:/bodies/1/mass",
     files={"s.json": with_body(1, mass=1e-300)})
case("a mass of 1e300", ["run", "s.json"], 2, "s.json:/bodies/1/mass",
     files={"s.json": with_body(1, mass=1e300)})
case("a speed of 1e300", ["run", "s.json"], 2, "s.json:/bodies/1/velocity",
     files={"s.json": with_body(1, velocity=[1e300, 0, 0])})
case("a position of 1e300", ["run", "s.json"], 2, "s.json:/bodies/1/position",
     files={"s.json": with_body(1, position=[1e300, 0, 0])})
case("a prism of 10^9 sides", ["run", "s.json"], 2, "s.json:/bodies/2/shape/sides",
     files={"s.json": with_body(2, shape={"type": "prism", "radius": 0.1, "half_height": 0.1,
                                         "sides": 1000000000})})
case("a hull of coplanar points", ["run", "s.json"], 2, "s.json:/bodies/2/shape",
     files={"s.json": with_body(2, shape={"type": "convex", "vertices": [
         [0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]]})})
case("a hull of one point repeated", ["run", "s.json"], 2, "s.json:/bodies/2/shape",
     files={"s.json": with_body(2, shape={"type": "convex", "vertices": [[0.1, 0.2, 0.3]] * 50})})
case("bodies overlapping at the start", ["run", "s.json", "--trace", "t.csv"], 2, "s.json:/bodies/2",
     files={"s.json": with_body(2, position=[0, 0, 0.5])}, absent=["t.csv"])
case("--end 1e300", ["run", "s.json", "--end", "1e300"], 2, "--end", files={"s.json": scene()})
case("--end nan", ["run", "s.json", "--end", "nan"], 2, "--end", files={"s.json": scene()})
case("--end -1", ["run", "s.json", "--end", "-1"], 2, "--end", files={"s.json": scene()})
case("--end 1e999", ["run", "s.json", "--end", "1e999"], 2, "--end", files={"s.json": scene()})

# --- 5. --set values.
case("--set /end_time=1e999", ["run", "s.json", "--set", "/end_time=1e999"], 2,
     "--set /end_time=1e999", files={"s.json": scene()})
case("--set a value that is not UTF-8", ["run", "s.json", "--set", b"/name=\xff\xfe"], 2,
     "not valid UTF-8", files={"s.json": scene()})
case("--set a key that is not UTF-8", ["run", "s.json", "--set", b"/\xff=1"], 2, "s.json",
     files={"s.json": scene()})
case("--set JSON 60,000 deep", ["run", "s.json", "--set", "/description=" + "[" * 60000 + "]" * 60000],
     2, "nested deeper", files={"s.json": scene()})
case("--set without =", ["run", "s.json", "--set", "/end_time"], 2, "--set /end_time",
     files={"s.json": scene()})
case("--set a relative pointer", ["run", "s.json", "--set", "end_time=1"], 2, "--set end_time=1",
     files={"s.json": scene()})
case("--set past the end of an array", ["run", "s.json", "--set", "/bodies/99/mass=1"], 2,
     "--set /bodies/99/mass=1", files={"s.json": scene()})
case("--set a word as an index", ["run", "s.json", "--set", "/bodies/x/mass=1"], 2,
     "--set /bodies/x/mass=1", files={"s.json": scene()})
case("--set a misspelt key", ["run", "s.json", "--set", "/settings/envelop=1e-4"], 2,
     "s.json:/settings/envelop", files={"s.json": scene()})
case("--set an =expression 30,000 deep", ["run", "s.json", "--set",
                                         "/end_time==" + "(" * 30000 + "1" + ")" * 30000],
     2, "s.json:/end_time", files={"s.json": scene()})

# --- 6. The reference, checked whole before the run: bowling for 10^5 s (some 15 minutes) with
# a bad reference must fail at once, or the case times out.
BOWLING = json.load(open(os.path.join(scenes, "bowling.json")))


def bowling(reference):
    doc = copy.deepcopy(BOWLING)
    doc["end_time"] = 1e5
    doc["reference"] = reference
    return doc


BALL = {"type": "bouncing_ball", "body": "ball", "restitution": 0.5, "gravity": 9.81}
case("a reference of an unknown type", ["run", "s.json", "--trace", "t.csv"], 2,
     "s.json:/reference/type", files={"s.json": bowling({"type": "nope"})},
     absent=["t.csv"], timeout=20)
case("an unknown key inside the reference", ["run", "s.json"], 2, "s.json:/reference/bodyy",
     files={"s.json": bowling(dict(BALL, bodyy=1))}, timeout=20)
case("a reference naming no body", ["run", "s.json"], 2, "s.json:/reference/body",
     files={"s.json": bowling(dict(BALL, body="nobody"))}, timeout=20)
case("a reference that is not an object", ["run", "s.json"], 2, "s.json:/reference",
     files={"s.json": bowling([1, 2])}, timeout=20)
case("a reference with restitution 1.5", ["run", "s.json"], 2, "s.json:/reference/restitution",
     files={"s.json": bowling(dict(BALL, restitution=1.5))}, timeout=20)
case("an impact_1d reference of one body with itself", ["run", "s.json"], 2,
     "s.json:/reference/body_b",
     files={"s.json": bowling({"type": "impact_1d", "body_a": "ball", "body_b": "ball",
                               "restitution": 0.5, "mass_a": 1, "mass_b": 1})}, timeout=20)
case("a reference with 1e999", ["run", "s.json"], 2, "s.json",
     files={"s.json": json.dumps(bowling(BALL)).replace('"restitution": 0.5', '"restitution": 1e999')},
     timeout=20)
case("a reference given by --set, bad", ["run", os.path.join(scenes, "bowling.json"), "--end", "1e5",
                                         "--set", '/reference={"type": "bouncing_ball"}'], 2,
     "bowling.json:/reference/body", timeout=20)
case("sweep with a bad reference runs no combination",
     ["sweep", "s.json", "--vary", "/settings/envelope=1e-4,2e-4", "--out", "o.csv"], 2,
     "s.json:/reference", files={"s.json": bowling({"type": "nope"})},
     absent=["o.csv"], timeout=20)

# --- 7. Outputs that never destroy.
def still_device(path):
    return lambda d: None if stat.S_ISCHR(os.stat(path).st_mode) else path + " is no longer a device"


case("--trace /dev/null", ["run", "s.json", "--trace", "/dev/null", "--events", "/dev/null"], 0,
     files={"s.json": scene()}, check=still_device("/dev/null"))
case("--trace -", ["run", "s.json", "--trace", "-"], 0, "scene", files={"s.json": scene()})
case("--trace /dev/stdout, a pipe", ["run", "s.json", "--trace", "/dev/stdout"], 0, "t,body,x",
     files={"s.json": scene()})
case("--trace a link to /dev/stdout, a pipe", ["run", "s.json", "--trace", "l.csv"], 0, "t,body,x",
     files={"s.json": scene()}, links={"l.csv": "/dev/stdout"}, absent=["l.csv.json"],
     check=lambda d: None if os.path.islink(os.path.join(d, "l.csv")) else "the link was replaced")
case("--trace /dev/stdout and --events -", ["run", "s.json", "--trace", "/dev/stdout", "--events", "-"],
     2, "--trace and --events", files={"s.json": scene()})
case("--trace and --events one file", ["run", "s.json", "--trace", "x", "--events", "x"], 2,
     "--trace and --events", files={"s.json": scene()}, absent=["x"])
case("--trace and --summary-json one file", ["run", "s.json", "--trace", "x", "--summary-json", "x"],
     2, "--trace and --summary-json", files={"s.json": scene()}, absent=["x"])
case("--trace in a missing directory", ["run", "s.json", "--trace", "no/t.csv"], 2, "no/t.csv",
     files={"s.json": scene()})
case("--trace is a directory", ["run", "s.json", "--trace", "."], 2, ".", files={"s.json": scene()})
case("--summary-json unwritable leaves no trace",
     ["run", "s.json", "--trace", "t.csv", "--summary-json", "no/s.json"], 2, "no/s.json",
     files={"s.json": scene()}, absent=["t.csv", "t.csv.json"])
case("--trace through a symlink", ["run", "s.json", "--trace", "link.csv"], 0,
     files={"s.json": scene(), "target.csv": "old\n"}, links={"link.csv": "target.csv"},
     check=lambda d: None if os.path.islink(os.path.join(d, "link.csv")) and
     open(os.path.join(d, "target.csv")).read().startswith("t,body")
     else "the link was replaced or its target not written")
case("a bad scene leaves an existing trace alone", ["run", "s.json", "--trace", "t.csv"], 2,
     "s.json:/end_time", files={"s.json": scene(end_time=-1), "t.csv": "precious\n"},
     check=lambda d: None if open(os.path.join(d, "t.csv")).read() == "precious\n"
     else "t.csv was changed")
case("plot --out /dev/null stays a device", ["plot", "t.csv", "--out", "/dev/null"], None,
     files={"t.csv": "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n0,a,0,0,0,1,0,0,0,0,0,0,0,0,0\n"},
     check=still_device("/dev/null"))
case("plot --out a directory leaves no temporary", ["plot", "t.csv", "--out", "."], None,
     files={"t.csv": "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n0,a,0,0,0,1,0,0,0,0,0,0,0,0,0\n"})
case("sweep --out and --plot one file",
     ["sweep", "s.json", "--vary", "/settings/envelope=1e-4", "--out", "x", "--plot", "x"], 2,
     "--out and --plot", files={"s.json": scene()}, absent=["x"])

# --- 8. sweep values.
case("sweep --vary 1e999", ["sweep", "s.json", "--vary", "/end_time=1e999", "--out", "o.csv"], 2,
     "--vary", files={"s.json": scene()}, absent=["o.csv"])
case("sweep --vary a value that is not UTF-8",
     ["sweep", "s.json", "--vary", b"/name=\xff", "--out", "o.csv"], 2, "not valid UTF-8",
     files={"s.json": scene()}, absent=["o.csv"])
case("sweep --vary nothing", ["sweep", "s.json", "--vary", "/end_time=", "--out", "o.csv"], 2,
     "--vary", files={"s.json": scene()}, absent=["o.csv"])
case("sweep --jobs 0", ["sweep", "s.json", "--vary", "/end_time=1", "--jobs", "0"], 2, "--jobs",
     files={"s.json": scene()})

# --- 9. Traces read back: compare and plot.
HEADER = "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n"
ROW = "{t},ball,0,0,{z},1,0,0,0,0,0,0,0,0,0\n"
good_trace = HEADER + "".join(ROW.format(t=k * 0.01, z=1 - 0.5 * 9.81 * (k * 0.01) ** 2)
                              for k in range(40))
drop = ["--reference", "bouncing_ball", "--param", "body=ball", "--param", "restitution=0.5",
        "--param", "gravity=9.81"]
case("a trace holding nan", ["compare", "t.csv"] + drop, 2, "t.csv:3",
     files={"t.csv": HEADER + ROW.format(t=0, z=1) + ROW.format(t=0.01, z="nan")})
case("a trace holding inf", ["compare", "t.csv"] + drop, 2, "t.csv:2",
     files={"t.csv": HEADER + ROW.format(t=0, z="inf")})
case("a trace whose time runs backwards", ["compare", "t.csv"] + drop, 2, "t.csv:3",
     files={"t.csv": HEADER + ROW.format(t=1, z=1) + ROW.format(t=0.5, z=1)})
case("a trace with a body name that is not UTF-8", ["compare", "t.csv"] + drop, 2, "t.csv:2",
     files={"t.csv": (HEADER + "0,\xff,0,0,1,1,0,0,0,0,0,0,0,0,0\n").encode("latin-1")})
case("a trace with a bad header", ["compare", "t.csv"] + drop, 2, "t.csv:1",
     files={"t.csv": "time,body\n"})
case("a trace that is empty", ["compare", "t.csv"] + drop, 2, "t.csv", files={"t.csv": ""})
case("a trace that does not exist", ["compare", "none.csv"] + drop, 2, "none.csv")
case("a directory as the trace", ["compare", "."] + drop, 2, ".: is a directory")
case("a directory as the events", ["compare", "t.csv", "--events", "."] + drop, 2,
     ".: is a directory", files={"t.csv": good_trace})
case("a trace with too few columns", ["compare", "t.csv"] + drop, 2, "t.csv:2",
     files={"t.csv": HEADER + "0,ball,1,2\n"})
case("compare --reference-from a directory", ["compare", "t.csv", "--reference-from", "."], 2, "is a directory",
     files={"t.csv": good_trace})
case("compare --reference-from a scene without a reference",
     ["compare", "t.csv", "--reference-from", "s.json"], 2, "s.json",
     files={"t.csv": good_trace, "s.json": scene()})
case("compare --param 1e999", ["compare", "t.csv", "--reference", "bouncing_ball", "--param", "body=ball",
                               "--param", "restitution=1e999", "--param", "gravity=9.81"], 2,
     "--param", files={"t.csv": good_trace})
case("compare --param not UTF-8", ["compare", "t.csv", "--reference", "bouncing_ball", "--param", b"body=\xff",
                                   "--param", "restitution=0.5", "--param", "gravity=9.81"], 2,
     "not valid UTF-8", files={"t.csv": good_trace})
case("compare a reference of an unknown type", ["compare", "t.csv", "--reference", "nope"], 2,
     "nope", files={"t.csv": good_trace})

# --- 10. Impact specs.
ROD = {"K": [[2.5, 0, -1.5], [0, 4, 0], [-1.5, 0, 2.5]], "u0": [0.5, 0, -1], "friction": 0.5,
       "restitution": 0.5, "law": "poisson"}
case("an impact spec that is fine", ["impact", "i.json"], 0, files={"i.json": ROD})
case("an impact spec's K 100,000 deep", ["impact", "i.json"], 2, "nested deeper",
     files={"i.json": json.dumps(ROD).replace('"K": [[2.5', '"K": ' + "[" * 100000 + "]" * 100000
                                              + ', "x": [[2.5')})
case("an impact spec with 1e999", ["impact", "i.json"], 2, "i.json",
     files={"i.json": json.dumps(ROD).replace("2.5]]", "1e999]]")})
case("an impact spec that is not JSON", ["impact", "i.json"], 2, "i.json", files={"i.json": "K=1"})
case("an impact spec with a K that is not symmetric", ["impact", "i.json"], 2, "i.json:/K",
     files={"i.json": dict(ROD, K=[[2.5, 1, -1.5], [0, 4, 0], [-1.5, 0, 2.5]])})
case("an impact spec with a K of nan-making size", ["impact", "i.json"], 2, "i.json:/K",
     files={"i.json": dict(ROD, K=[[1e308, 0, 0], [0, 1e308, 0], [0, 0, 1e308]])})
case("an impact spec on standard input, deep", ["impact", "-"], 2, "nested deeper",
     stdin=deep.encode())
case("an impact spec with an unknown key", ["impact", "i.json"], 2, "i.json:/Kk",
     files={"i.json": dict(ROD, Kk=1)})
case("an impact spec with a NUL in a key (found by fuzz_impact)", ["impact", "i.json"], 2, "i.json:/K",
     files={"i.json": json.dumps(ROD).replace('"friction"', '"K\\u0000x"')})
case("a scene with a NUL in a key", ["run", "s.json"], 2, "s.json:/",
     files={"s.json": json.dumps(scene())[:-1] + ', "a\\u0000b": 1}'})
case("a body with a NUL in its name overlapping another", ["run", "s.json"], 2, "s.json:/bodies/2",
     files={"s.json": json.dumps(with_body(2, position=[0, 0, 0.5], name="x\u0000y"))})

# --- 11. The command line itself.
case("no command", [], 2)
case("an unknown command", ["fly"], 2, "subcommand")
case("an unknown option", ["run", "s.json", "--trase", "t.csv"], 2, "--trase",
     files={"s.json": scene()}, absent=["t.csv"])
case("run without a scene", ["run"], 2, "scene")
case("--end not a number", ["run", "s.json", "--end", "soon"], 2, "--end", files={"s.json": scene()})

# --- 12. Promises kept on a valid scene (the exit code and the files).
case("a valid scene writes trace, sidecar and events",
     ["run", "s.json", "--trace", "t.csv", "--events", "e.csv", "--summary-json", "j.json"], 0,
     files={"s.json": scene()}, exists=["t.csv", "t.csv.json", "e.csv", "j.json"])
case("--strict on a valid scene", ["run", "s.json", "--strict", "--trace", "t.csv"], 0,
     files={"s.json": scene()}, exists=["t.csv"])
case("a convex hull of 20,000 points is built in seconds", ["run", "s.json", "--end", "0.01"], 0,
     files={"s.json": with_body(2, shape={"type": "convex", "vertices": [
         [0.1 * __import__("math").cos(i * 2.399963) * __import__("math").sqrt(1 - ((2 * i + 1) / 20000 - 1) ** 2),
          0.1 * __import__("math").sin(i * 2.399963) * __import__("math").sqrt(1 - ((2 * i + 1) / 20000 - 1) ** 2),
          0.1 * ((2 * i + 1) / 20000 - 1)] for i in range(20000)]})}, timeout=60)


def run_case(c, root):
    d = tempfile.mkdtemp(dir=root)
    for name, content in c["files"].items():
        if isinstance(content, (dict, list)):
            content = json.dumps(content)
        if isinstance(content, str):
            content = content.encode()
        with open(os.path.join(d, name), "wb") as f:
            f.write(content)
    for name, target in c["links"].items():
        os.symlink(target, os.path.join(d, name))
    args = [palpable.encode()] + [a if isinstance(a, bytes) else a.encode() for a in c["args"]]
    start = time.monotonic()
    try:
        p = subprocess.run(args, cwd=d, input=c["stdin"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, timeout=c["timeout"])
    except subprocess.TimeoutExpired:
        return "no exit within %d s" % c["timeout"]
    elapsed = time.monotonic() - start
    err = p.stderr.decode("utf-8", "replace")
    problems = []
    if p.returncode < 0:
        problems.append("killed by signal %d" % -p.returncode)
    elif c["code"] is not None and p.returncode != c["code"]:
        problems.append("exit %d, expected %d" % (p.returncode, c["code"]))
    elif c["code"] is None and p.returncode not in (0, 1, 2):
        problems.append("exit %d" % p.returncode)
    if p.returncode == 1 and c["code"] == 2 or "what():" in err or "terminate called" in err:
        problems.append("a library message, not bad input")
    if c["fragment"] and c["fragment"] not in err + p.stdout.decode("utf-8", "replace")[:2000]:
        problems.append("stderr lacks %r" % c["fragment"])
    for name in c["exists"]:
        if not os.path.exists(os.path.join(d, name)):
            problems.append(name + " missing")
    for name in c["absent"]:
        if os.path.lexists(os.path.join(d, name)):
            problems.append(name + " exists")
    leftovers = glob.glob(os.path.join(d, "**", "*.tmp-*"), recursive=True)
    if leftovers:
        problems.append("temporary left: " + ", ".join(os.path.basename(x) for x in leftovers))
    if c["check"]:
        why = c["check"](d)
        if why:
            problems.append(why)
    if problems:
        return "; ".join(problems) + " [stderr: " + err.strip()[:300] + "]"
    return None


def main():
    root = tempfile.mkdtemp(prefix="hostile_corpus.")
    failed = 0
    ran = 0
    for c in cases:
        if only and only not in c["name"]:
            continue
        ran += 1
        why = run_case(c, root)
        if why:
            failed += 1
            print("FAIL %s: %s" % (c["name"], why))
        else:
            print("ok   %s" % c["name"])
    subprocess.run(["rm", "-rf", root])
    print("%d cases, %d failed" % (ran, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
