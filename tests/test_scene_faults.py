"""Issue 10, scene parsing: a corpus of malformed scenes, each a SceneError whose message starts
with the key path (or the file) and says what was expected; never a traceback, never a silent
"ok".

A case is one line: (description, source, expected message fragment).  The source is TOML
text appended to BASE, an (old, new) replacement in BASE's text, or a dict of changes to BASE
keyed by dotted paths ("body.0.elements"; "constraint+" appends to an array of tables; DELETE
removes a key; "@base": "2d" starts from BASE_2D).  The message must start with the
fragment's key path (the text before its first ":").
"""

from __future__ import annotations

import copy
import datetime
import math
import random
import tomllib

import numpy as np
import pytest

from runtime import Revolute
from runtime.model.bodies import Material
from runtime.model.errors import SceneError
from runtime.model.scene import load_scene, parse_scene

BASE = """
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0

[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = { height = 0.1, width = 0.1 }
elements = 10
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[body]]
name = "link"
element = "beam3d"
material = "steel"
section = { height = 0.1, width = 0.1 }
elements = 2
start = [1.0, 0.0, 0.0]
end = [2.0, 0.0, 0.0]

[[constraint]]
type = "clamp"
node = "beam:0"

[[load]]
type = "point_force"
node = "link:-1"
force = [0.0, -10.0, 0.0]

[[sensor]]
name = "tip_y"
type = "displacement"
node = "link:-1"
component = "y"

[[sensor]]
name = "U"
type = "strain_energy"

[analysis.static]
[analysis.modal]
[analysis.dynamic]
t_end = 0.01
step = 0.001
"""

BASE_2D = """
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0

[[body]]
name = "a"
element = "beam2d"
material = "steel"
section = { height = 0.1, width = 0.1 }
elements = 2
start = [0.0, 0.0]
end = [1.0, 0.0]

[[body]]
name = "b"
element = "beam2d"
material = "steel"
section = { height = 0.1, width = 0.1 }
elements = 2
start = [1.0, 0.0]
end = [2.0, 0.0]

[[constraint]]
type = "pin"
node = "a:0"

[[constraint]]
type = "revolute"
nodes = ["a:-1", "b:0"]
"""

DELETE = "<delete this key>"
HUGE = 10**400   # a TOML integer of 401 digits (tomllib reads it; no float holds it)


def rot(node: str) -> dict:
    return {"type": "prescribed_rotation", "node": node,
            "angle": {"type": "constant_rate", "omega": 1.0}}


def joint(a: str, b: str, kind: str = "spherical") -> dict:
    return {"type": kind, "nodes": [a, b]}


def hold(kind: str, node: str) -> dict:
    return {"type": kind, "node": node}


C = {"body+": {"name": "c", "element": "beam3d", "material": "steel", "elements": 1,
               "section": {"height": 0.1, "width": 0.1}, "start": [1.0, 0.0, 0.0],
               "end": [1.0, 1.0, 0.0]}}
DYN = "analysis.dynamic"
LAW = "load.0.time_law"

# a rigid body after BASE's two beams
RIGID = ('[[body]]\ntype = "rigid"\nname = "bar"\nmass = 1.0\ninertia = [1, 1, 1]\n'
         'position = [5, 0, 0]\n')
# a plate body after BASE's two beams (body[2])
PLATE = """
[[body]]
name = "sheet"
element = "plate3d"
material = "steel"
section = { thickness = 0.01 }
rectangle = { corner = [0.0, 5.0, 0.0], size = [1.0, 0.5], grid = [4, 2] }
"""

CASES = [
    # plates: rectangle bodies, grid indices, edges, line forces
    ("plate grid of floats", PLATE.replace("[4, 2]", "[4.0, 2]"),
     "body[2].rectangle.grid[0]: expected an integer, got 4.0 (a float; write 4)"),
    ("plate without rectangle", PLATE.replace("rectangle =", "#"),
     "body[2].rectangle: missing required key"),
    ("plate with a beam section", PLATE.replace("thickness = 0.01", "height = 0.1, width = 0.1"),
     "body[2].section.height: unknown key; expected one of thickness"),
    ("plate thickness negative", PLATE.replace("0.01", "-0.01"),
     "body[2].section.thickness: expected a positive number"),
    ("plate grid too large", PLATE.replace("[4, 2]", "[100000, 100000]"),
     "body[2].rectangle.grid: 10000000012 elements"),
    ("plate size zero", PLATE.replace("[1.0, 0.5]", "[1.0, 0.0]"),
     "body[2].rectangle.size: expected two positive finite sides"),
    ("edge as a node", PLATE + '[[constraint]]\ntype = "pin"\nnode = "sheet:x=0"\n',
     "constraint[1].node: expected an integer node index"),
    ("clamp without node or edge", PLATE + '[[constraint]]\ntype = "clamp"\n',
     "constraint[1]: expected either node"),
    ("edge on a hub", PLATE + '[[constraint]]\ntype = "prescribed_rotation"\n'
     'edge = "sheet:x=0"\nangle = { type = "constant_rate", omega = 1.0 }\n',
     "constraint[1].edge: unknown key"),
    ("line force without a force", PLATE + '[[load]]\ntype = "line_force"\nedge = "sheet:y=0"\n',
     "load[1].force_per_length: missing required key"),
    ("line force of 2 components", PLATE + '[[load]]\ntype = "line_force"\n'
     'edge = "sheet:y=0"\nforce_per_length = [1.0, 2.0]\n',
     "load[1].force_per_length: expected a list of 3 numbers"),
    ("line force on a beam", PLATE + '[[load]]\ntype = "line_force"\nedge = "beam:x=0"\n'
     'force_per_length = [1.0, 2.0, 3.0]\n', 'load[1].edge: body "beam" is a line'),
    ("grid index out of range", PLATE + '[[sensor]]\nname = "c"\ntype = "position"\n'
     'node = "sheet:5,0"\ncomponent = "z"\n',
     'sensor[2].node: grid index I 5 out of range for body "sheet" with 5 node columns'),
    ("grid index on a beam", PLATE + '[[sensor]]\nname = "c"\ntype = "position"\n'
     'node = "beam:1,0"\ncomponent = "z"\n', "sensor[2].node: expected an integer node index"),

    # 1. wrong "ok"
    ("clamp and prescribed rotation on one node", {"constraint+": rot("beam:0")},
     "constraint[1].node: constraint[0] (clamp) and constraint[1] (prescribed_rotation) on node "
     "beam:0: contradictory"),
    ("two prescribed rotations, one node spelt twice",
     {"constraint": [rot("beam:0"), rot("beam:-11")]},
     "constraint[1].node: constraint[0] (prescribed_rotation) and constraint[1] "
     "(prescribed_rotation) on node beam:0: a node has at most one prescribed_rotation"),
    ("t_end not a multiple of step", {f"{DYN}.t_end": 0.0105},
     "analysis.dynamic.t_end: expected an integer multiple of analysis.dynamic.step = 0.001 s, "
     "got t_end = 0.0105 s (t_end / step = 10.5: the run would stop at 0.01 s); nearest valid: "
     "t_end = 0.01 or 0.011 s, or step = 0.000954545454545 or 0.00105 s"),
    ("output_every not a multiple of step", {f"{DYN}.output_every": 0.0025},
     "analysis.dynamic.output_every: expected an integer multiple of analysis.dynamic.step = "
     "0.001 s, got output_every = 0.0025 s (output_every / step = 2.5); nearest valid: "
     "output_every = 0.002 or 0.003 s"),
    ("node index in Arabic-Indic digits", {"constraint.0.node": "beam:\u0663"},
     "constraint[0].node: expected an integer node index after \":\" (ASCII digits"),
    ("node index with a blank", {"constraint.0.node": "beam: 1"},
     "constraint[0].node: expected an integer node index"),
    ("node index with a trailing blank", {"constraint.0.node": "beam:1 "},
     "constraint[0].node: expected an integer node index"),
    ("node index with an underscore", {"constraint.0.node": "beam:1_0"},
     "constraint[0].node: expected an integer node index"),
    ("node index with a plus sign", {"constraint.0.node": "beam:+1"},
     "constraint[0].node: expected an integer node index"),
    ("node index with a leading zero", {"constraint.0.node": "beam:01"},
     "constraint[0].node: expected an integer node index"),
    ("node index -0 (first or last?)", {"constraint.0.node": "beam:-0"},
     "constraint[0].node: expected an integer node index"),
    ("node index of 5000 digits", {"constraint.0.node": "beam:" + "9" * 5000},
     "constraint[0].node: node index 99999999999999999999... out of range for body \"beam\" "
     "with 11 nodes"),
    ("node index out of range, negative (regression)", {"constraint.0.node": "beam:-12"},
     "constraint[0].node: node index -12 out of range for body \"beam\" with 11 nodes "
     "(0..10 or -11..-1)"),
    # 2. redundant or contradictory constraints
    ("joint of a node with itself, spelt twice (regression)",
     {"constraint+": joint("beam:-1", "beam:10")},
     "constraint[1].nodes: expected two different nodes, got beam:10 twice"),
    ("the same joint twice, nodes swapped",
     {"constraint": [joint("beam:-1", "link:0"), joint("link:0", "beam:10")]},
     "constraint[1].nodes: the same joint as constraint[0] (nodes link:0 and beam:10)"),
    ("a joint between two clamped nodes",
     {"constraint": [hold("clamp", "beam:-1"), hold("pin", "link:0"), joint("beam:-1", "link:0")]},
     "constraint[2].nodes: redundant joint: both positions are already held, beam:10 by "
     "constraint[0] (clamp) and link:0 by constraint[1] (pin)"),
    ("a joint to a rigid hub and a clamped node",
     {"constraint": [hold("clamp", "beam:-1"), rot("link:0"), joint("beam:-1", "link:0")]},
     "constraint[2].nodes: redundant joint: both positions are already held"),
    ("pin and clamp on one node", {"constraint+": hold("pin", "beam:0")},
     "constraint[1].node: constraint[0] (clamp) and constraint[1] (pin) on node beam:0: "
     "redundant: the clamp holds every coordinate of the node"),
    ("pin and prescribed rotation on one node",
     {"constraint": [rot("beam:0"), hold("pin", "beam:0")]},
     "constraint[1].node: constraint[0] (prescribed_rotation) and constraint[1] (pin) on node "
     "beam:0: redundant: the prescribed rotation already holds the node's position"),
    ("a cycle of joints",
     {**C, "constraint+": [joint("beam:-1", "link:0"), joint("link:0", "c:0"),
                           joint("c:0", "beam:-1")]},
     "constraint[3].nodes: redundant joint: c:0 and beam:10 are already tied together through "
     "constraint[1], constraint[2]"),
    ("a joint closing a path to the ground",
     {**C, "constraint+": [hold("pin", "beam:-1"), joint("beam:-1", "link:0"),
                           hold("pin", "c:0"), joint("link:0", "c:0")]},
     "constraint[4].nodes: redundant joint: link:0 and c:0 are already held in place through "
     "constraint[0], constraint[1], constraint[2], constraint[3]"),
    ("joint nodes apart", {"constraint+": joint("beam:5", "link:0")},
     "constraint[1].nodes: the nodes of a joint share their position, expected two nodes at the "
     "same place in the reference, got beam:5 at (0.5, 0, 0) and link:0 at (1, 0, 0), 0.5 m apart"),
    ("revolute axis in 2D", {"@base": "2d", "constraint.1.axis": [0.0, 0.0, 1.0]},
     "constraint[1].axis: only allowed in 3D scenes (a 2D revolute joint turns about z)"),
    ("point force on a clamped node", {"load.0.node": "beam:0"},
     "load[0].node: the position of beam:0 is held by constraint[0] (clamp): a force there does "
     "nothing"),
    ("every coordinate held",
     {"body.0.elements": 1, "body.1.elements": 1, "load": [],
      "constraint": [hold("clamp", n) for n in ("beam:0", "beam:1", "link:0", "link:1")]},
     "constraint: the constraints hold all 48 coordinates of the model"),
    # 3. runaway sizes
    ("ten million elements", {"body.0.elements": 10_000_000},
     "body[0].elements: 10000002 elements (120000048 coordinates) need about 1.37e+03 GiB of "
     "memory (estimate: 256 B per entry of the 24x24 element matrices), over the limit of "
     "24 GiB; expected at most about 174762 beam3d elements"),
    ("elements as a float", {"body.0.elements": 1e20},
     "body[0].elements: expected an integer, got 1e+20 (a float)"),
    ("elements as an integral float", {"body.0.elements": 10.0},
     "body[0].elements: expected an integer, got 10.0 (a float; write 10)"),
    ("elements of 401 digits", {"body.0.elements": HUGE},
     "body[0].elements: ~1e400 elements (~1e401 coordinates) need about ~1e396 GiB"),
    ("load_steps as a float", {"analysis.static.load_steps": 1e9},
     "analysis.static.load_steps: expected an integer, got 1000000000.0 (a float; write "
     "1000000000)"),
    ("a billion load steps", {"analysis.static.load_steps": 10**9},
     "analysis.static.load_steps: expected at most 100000000 load increments"),
    ("load steps times elements", {"analysis.static.load_steps": 10**8, "body.0.elements": 1000},
     "analysis.static.load_steps: 100000000 load increments of 1002 elements exceed the limit of "
     "1e+10 element-steps"),
    ("1e24 time steps", {f"{DYN}.t_end": 1e21},
     "analysis.dynamic.step: t_end / step = 1e+24 time steps exceed the limit of 1e+08; "
     "expected step >= 1e+13 s"),
    ("infinitely many time steps", {f"{DYN}.t_end": 1e300, f"{DYN}.step": 1e-300},
     "analysis.dynamic.step: t_end / step = inf time steps exceed the limit"),
    ("element-steps", {f"{DYN}.t_end": 10.0, f"{DYN}.step": 1e-5, "body.0.elements": 10_000},
     "analysis.dynamic.step: 1000000 time steps of 10002 elements exceed the limit of 1e+10 "
     "element-steps"),
    ("a billion modes", {"analysis.modal.modes": 10**9},
     "analysis.modal.modes: expected at most 1000 modes"),
    ("more modes than degrees of freedom", {"analysis.modal.modes": 500},
     "analysis.modal.modes: expected at most the 156 degrees of freedom of the model, got 500"),
    ("dense modal analysis with joints",
     {"body.0.elements": 20_000, "constraint+": joint("beam:-1", "link:0")},
     "analysis.modal: with joints, a modal analysis works on dense 240036x240036 matrices"),
    ("a billion static iterations", {"analysis.static.max_iterations": 10**9},
     "analysis.static.max_iterations: expected at most 1000 Newton iterations"),
    ("a billion dynamic iterations", {f"{DYN}.max_iterations": 10**9},
     "analysis.dynamic.max_iterations: expected at most 1000 Newton iterations"),
    ("1e8 output rows (every step)", {f"{DYN}.t_end": 1000.0, f"{DYN}.step": 1e-5},
     "analysis.dynamic.output_every (absent: every step): 100000002 rows of 3 columns in "
     "timeseries.csv exceed the limit of 1e+08 values"),
    ("1e8 output rows", {f"{DYN}.t_end": 1000.0, f"{DYN}.step": 1e-5, f"{DYN}.output_every": 2e-5},
     "analysis.dynamic.output_every: 50000002 rows of 3 columns in timeseries.csv exceed the "
     "limit of 1e+08 values (the file is read back whole for the plots); expected output_every "
     ">= 3e-05 s"),
    ("Gauss order of a million", {"body.0.quadrature": [1_000_000, 3, 3]},
     "body[0].quadrature: expected a list of 3 positive integers of at most 64"),
    ("1001 sensors",
     {"sensor": [{"name": f"s{i}", "type": "kinetic_energy"} for i in range(1001)]},
     "sensor: expected at most 1000 sensors (one CSV column and one PNG plot each), got 1001"),
    # 5. material laws
    ("unknown material law", {"material.steel.law": "neo"},
     'material.steel.law: unknown material law "neo"; expected one of svk, ecm'),
    ("shear correction with svk", {"material.steel.shear_correction": 0.85},
     'material.steel.shear_correction: only meaningful with law = "ecm", got law = "svk"'),
    ("zero shear correction", {"material.steel.law": "ecm", "material.steel.shear_correction": 0},
     "material.steel.shear_correction: expected a positive number, got 0"),
    ("negative damping", {"material.steel.damping": -1e-3},
     "material.steel.damping: expected a Kelvin-Voigt coefficient alpha >= 0 (s), got -0.001"),
    ("NaN damping", {"material.steel.damping": math.nan},
     "material.steel.damping: expected a finite number, got nan"),
    ("boolean damping", {"material.steel.damping": True},
     "material.steel.damping: expected a finite number, got true"),
    # 6. sensors and frequency_of
    ("frequency_of an unknown sensor", {f"{DYN}.frequency_of": "tip"},
     'analysis.dynamic.frequency_of: no sensor called "tip"; expected one of tip_y, U'),
    ("frequency_of without sensors", {"sensor": [], f"{DYN}.frequency_of": "tip"},
     'analysis.dynamic.frequency_of: no sensor called "tip"; expected a [[sensor]] name '
     "(none defined)"),
    ("too few samples for a frequency",
     {f"{DYN}.frequency_of": "tip_y", f"{DYN}.frequency_after": 0.005},
     "analysis.dynamic.frequency_after: the frequency estimate needs at least 8 output samples "
     "from frequency_after = 0.005 s to t_end = 0.01 s, got 6"),
    ("a 300-character sensor name", {"sensor.1.name": "x" * 300},
     "sensor[1].name: expected letters, digits, _ . and - starting with a letter, digit or _, "
     "at most 64 characters"),
    ("sensor names equal ignoring case", {"sensor.1.name": "TIP_Y"},
     'sensor[1].name: duplicate sensor name "TIP_Y" (as "tip_y", ignoring case)'),
    ("sensor called like the energy plot", {"sensor.1.name": "Energies"},
     "sensor[1].name: expected a name other than the reserved t, energies"),
    ("sensor called like a device", {"sensor.1.name": "nul.x"},
     "sensor[1].name: expected a name other than the reserved"),
    ("sensor name with a slash", {"sensor.1.name": "a/b"}, "sensor[1].name: expected letters"),
    ("hidden sensor name", {"sensor.1.name": ".U"}, "sensor[1].name: expected letters"),
    ("sensor name with NUL", {"sensor.1.name": "U\x00"}, "sensor[1].name: expected letters"),
    # 7. engine and Newton variant
    ("unknown engine", {"solver.engine": "jit"},
     'solver.engine: unknown engine "jit"; expected one of compiled, python'),
    ("unknown Newton variant", {f"{DYN}.newton": "quasi"},
     'analysis.dynamic.newton: unknown Newton iteration "quasi"; expected one of full, modified'),
    # 8. types and values everywhere
    ("E of 401 digits", {"material.steel.E": HUGE},
     "material.steel.E: expected a positive number, got an integer of about 401 digits"),
    ("E infinite", ("E = 2.1e11", "E = inf"),
     "material.steel.E: expected a positive number, got inf"),
    ("E as a date", ("E = 2.1e11", "E = 1979-05-27"),
     "material.steel.E: expected a positive number, got 1979-05-27 (a date)"),
    ("a sensor name repeated in appended TOML",
     '[[sensor]]\nname = "tip_y"\ntype = "kinetic_energy"\n',
     'sensor[2].name: duplicate sensor name "tip_y"; sensor names name files'),
    ("start with a 401-digit coordinate", {"body.0.start": [0, 0, HUGE]},
     "body[0].start: expected a list of 3 numbers"),
    ("ramp duration of 401 digits", {LAW: {"type": "cosine_ramp", "duration": HUGE}},
     "load[0].time_law.duration: expected a positive number, got an integer of about 401"),
    ("table point of 401 digits", {LAW: {"type": "table", "points": [[0, HUGE]]}},
     "load[0].time_law.points[0]: expected a pair [t, v] of finite numbers"),
    ("unsorted table", {LAW: {"type": "table", "points": [[1, 0], [0, 1]]}},
     "load[0].time_law.points[1]: times must be strictly increasing, got 0 after 1"),
    ("duplicate table times", {LAW: {"type": "table", "points": [[0, 0], [1, 1], [1, 2]]}},
     "load[0].time_law.points[2]: times must be strictly increasing, got 1 after 1"),
    ("table point of three numbers", {LAW: {"type": "table", "points": [[0, 1, 2]]}},
     "load[0].time_law.points[0]: expected a pair"),
    ("flat table", {LAW: {"type": "table", "points": [0, 1]}},
     "load[0].time_law.points[0]: expected a pair [t, v] of finite numbers, got 0"),
    ("time law as a string", {LAW: "cosine"}, "load[0].time_law: expected a table"),
    ("time law type as a number", {LAW: {"type": 3}}, "load[0].time_law.type: unknown time law 3"),
    ("axis of 401 digits", {"constraint": [{**rot("beam:0"), "axis": [0, 0, HUGE]}]},
     "constraint[0].axis: expected a list of 3 numbers"),
    ("nu as a boolean", {"material.steel.nu": True},
     "material.steel.nu: expected a finite number, got true"),
    ("section as a list", {"body.0.section": [0.1, 0.1]}, "body[0].section: expected a table"),
    ("height as a table", {"body.0.section.height": {"x": 1}},
     "body[0].section.height: expected a positive number, got a table"),
    ("start as a string", {"body.0.start": "0,0,0"}, "body[0].start: expected a list of 3"),
    ("elements as a string", {"body.0.elements": "10"},
     'body[0].elements: expected a positive integer, got "10"'),
    ("elements as a list", {"body.0.elements": [10]},
     "body[0].elements: expected a positive integer, got [10]"),
    ("negative elements", {"body.0.elements": -3},
     "body[0].elements: expected a positive integer, got -3"),
    ("body name with a newline", {"body.1.name": "li\nnk"},
     'body[1].name: expected a body name of printable characters without blanks at either '
     'end, got "li\\u000ank"'),
    ("body name with a blank", {"body.1.name": "link "},
     "body[1].name: expected a body name of printable characters"),
    ("300-character body name", {"body.1.name": "b" * 300},
     "body[1].name: expected a body name of at most 64 characters, got 300 characters"),
    ("empty material name", {"material": {"": {"E": 1.0, "nu": 0.0, "rho": 1.0},
                                          "steel": {"E": 1.0, "nu": 0.0, "rho": 1.0}}},
     'material."": expected a non-empty string, got ""'),
    ("title with a newline", {"title": "a\nb"},
     "title: expected one line of printable text of at most 200 characters"),
    ("title as a table", {"title": {"a": 1}}, "title: expected a non-empty string, got a table"),
    ("infinite arc", {"body.0": {**tomllib.loads(BASE)["body"][0], "start": DELETE,
                                 "end": DELETE, "arc": {"center": [1e308, 0.0, 0.0],
                                                        "radius": 1e308, "angle_deg": 90}}},
     "body[0].arc.radius: expected an arc of finite extent"),
    ("infinitely long body", {"body.1.end": [1e308, 1e308, 0.0]},
     "body[1].end: expected a body of finite length"),
    ("Newton tolerance of 10", {f"{DYN}.tolerance": 10.0},
     "analysis.dynamic.tolerance: expected a relative Newton tolerance in [1e-15, 0.01]"),
    ("Newton tolerance of 1e-300", {"analysis.static.tolerance": 1e-300},
     "analysis.static.tolerance: expected a relative Newton tolerance in [1e-15, 0.01]"),
    ("output_every as a boolean", {f"{DYN}.output_every": True},
     "analysis.dynamic.output_every: expected a positive number, got true"),
    ("step as a string", {f"{DYN}.step": "1e-3"},
     'analysis.dynamic.step: expected a positive number, got "1e-3"'),
    ("analysis as a number", {"analysis": 5}, "analysis: expected a table, got 5"),
    ("static analysis as a list", {"analysis.static": []},
     "analysis.static: expected a table, got []"),
    ("solver as a string", {"solver": "fast"}, 'solver: expected a table, got "fast"'),
    ("constraint as a table", {"constraint": {"type": "clamp"}},
     "constraint: expected an array of tables"),
    ("force with a string", {"load.0.force": [0, "1", 0]}, "load[0].force: expected a list of 3"),
    ("component as a number", {"sensor.0.component": 1},
     "sensor[0].component: unknown component 1"),
    ("energy of a list of bodies", {"sensor.1.body": ["beam"]},
     'sensor[1].body: unknown body ["beam"]'),
    ("frequency_of as a number", {f"{DYN}.frequency_of": 3},
     "analysis.dynamic.frequency_of: expected a non-empty string, got 3"),
    ("quadrature with a boolean", {"body.0.quadrature": [5, 3, True]},
     "body[0].quadrature: expected a list of 3 positive integers"),
    ("quadrature as a number", {"body.0.quadrature": 5},
     "body[0].quadrature: expected a list of 3 positive integers"),
    ("material as a number", {"material.steel": 5}, "material.steel: expected a table, got 5"),
    # multibody: prescribed joint motion, joints and force elements of rigid bodies
    ("driven angle not 0 at t = 0", RIGID + '[[constraint]]\ntype = "body_revolute"\n'
     'body = "bar"\nangle = {type = "constant", value = 0.5}\n',
     "constraint[1].angle: expected a law that is 0 at t = 0"),
    ("driven displacement as a number", RIGID + '[[constraint]]\ntype = "body_prismatic"\n'
     'body = "bar"\ndisplacement = 0.1\n', "constraint[1].displacement: expected a table"),
    ("prismatic joint on its own body", RIGID + '[[constraint]]\ntype = "body_prismatic"\n'
     'body = "bar"\nother = "bar"\n', "constraint[1].other: expected another body"),
    ("cylindrical joint of a meshed body", RIGID + '[[constraint]]\n'
     'type = "body_cylindrical"\nbody = "beam"\n',
     "constraint[1].body: expected the name of a rigid body"),
    ("universal joint's axes not normal", RIGID + '[[constraint]]\ntype = "body_universal"\n'
     'body = "bar"\nother_axis = [0, 0.6, 0.8]\n',
     "constraint[1].other_axis: expected an axis normal to the body's axis"),
    ("torsional spring of negative stiffness", RIGID + '[[load]]\n'
     'type = "torsional_spring"\nbody = "bar"\nstiffness = -1.0\n',
     "load[1].stiffness: expected a number >= 0"),
    ("torsional spring to a node and a body", RIGID + '[[load]]\n'
     'type = "torsional_spring"\nbody = "bar"\nstiffness = 1.0\nnode = "beam:-1"\n'
     'other = "bar"\n', "load[1].other: expected a node or another body"),
    ("bushing of five entries", RIGID + '[[load]]\ntype = "bushing"\nbody = "bar"\n'
     'stiffness = [1, 2, 3, 4, 5]\n',
     "load[1].stiffness: expected six diagonal entries or a 6 x 6 matrix"),
    ("bushing damping not positive", RIGID + '[[load]]\ntype = "bushing"\nbody = "bar"\n'
     'stiffness = [1, 1, 1, 1, 1, 1]\ndamping = [1, 1, 1, 1, 1, -1]\n',
     "load[1].damping: expected a positive semi-definite matrix"),
]
def _apply(data: dict, changes: dict) -> None:
    for key, value in changes.items():
        if key == "@base":
            continue
        append = key.endswith("+")
        *parents, last = key.rstrip("+").split(".")
        target = data
        for part in parents:
            target = target[int(part)] if isinstance(target, list) else target.setdefault(part, {})
        if isinstance(value, dict):
            value = {k: v for k, v in value.items() if v is not DELETE}
        if append:
            target.setdefault(last, []).extend(value if isinstance(value, list) else [value])
        elif isinstance(target, list):
            target[int(last)] = value
        elif value is DELETE:
            del target[last]
        else:
            target[last] = value


def scene_data(source) -> dict:
    if isinstance(source, str):
        return tomllib.loads(BASE + source)
    if isinstance(source, tuple):
        old, new = source
        assert old in BASE
        return tomllib.loads(BASE.replace(old, new))
    data = tomllib.loads(BASE_2D if source.get("@base") == "2d" else BASE)
    _apply(data, copy.deepcopy(source))
    return data


def test_bases_are_valid():
    scene = parse_scene(tomllib.loads(BASE))
    assert [c.type for c in scene.constraints] == ["clamp"]
    scene = parse_scene(tomllib.loads(BASE_2D))
    assert isinstance(scene.constraints[1], Revolute)


@pytest.mark.parametrize("description, source, message", CASES, ids=[c[0] for c in CASES])
def test_malformed_scene_is_a_named_scene_error(description, source, message):
    data = scene_data(source)
    with pytest.raises(SceneError) as info:
        parse_scene(data)
    text = str(info.value)
    assert message in text
    assert text.startswith(message.split(":")[0] + ":"), text
    assert "\n" not in text and len(text) < 1000


# --------------------------------------------------------------------------- new keys

def test_material_law_shear_correction_and_damping():
    scene = parse_scene(scene_data({"material.steel.law": "ecm",
                                    "material.steel.shear_correction": 0.85,
                                    "material.steel.damping": 2e-3}))
    assert scene.materials["steel"] == Material("steel", 2.1e11, 0.3, 7800.0, "ecm", 0.85, 2e-3)
    default = parse_scene(scene_data({})).materials["steel"]
    assert (default.law, default.shear_correction, default.damping) == ("svk", None, 0.0)
    assert parse_scene(scene_data({"material.steel.law": "ecm"})).materials[
        "steel"].shear_correction is None


def test_engine_and_newton_keys():
    scene = parse_scene(scene_data({"solver.engine": "python", f"{DYN}.newton": "modified"}))
    assert scene.solver.engine == "python" and scene.dynamic.newton == "modified"
    default = parse_scene(scene_data({}))
    assert default.solver.engine is None and default.dynamic.newton == "auto"


def test_valid_edge_cases_still_parse():
    # multiples within the relative tolerance; last node spelt both ways; a joint to a hub
    ok = {f"{DYN}.t_end": 0.3, f"{DYN}.step": 2.5e-3, f"{DYN}.output_every": 0.005,
          "constraint+": [joint("beam:10", "link:0")], "load.0.node": "link:1"}
    scene = parse_scene(scene_data(ok))
    assert scene.dynamic.t_end == 0.3
    assert parse_scene(scene_data({"constraint": [rot("link:0"), joint("beam:-1", "link:0")]}))
    assert parse_scene(scene_data({"sensor.1.name": "U-total.1"})).sensors[1].name == "U-total.1"
    # an axis whose squared norm overflows is still normalised
    scene = parse_scene(scene_data({"constraint": [{**rot("beam:0"), "axis": [1e200, 1e200, 0]}]}))
    assert scene.constraints[0].axis == pytest.approx((math.sqrt(0.5), math.sqrt(0.5), 0.0))


# --------------------------------------------------------------------------- files

def _write(tmp_path, content: bytes | str | None, name: str = "scene.toml"):
    path = tmp_path / name
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    elif content is not None:
        path.write_bytes(content)
    return path


FILE_CASES = [
    ("not UTF-8 (a stray byte)", b'title = "x"\n\xff = 1\n',
     "not UTF-8 text: byte 0xff at offset 12 (line 2, column 1)"),
    ("Latin-1 text", b'title = "caf\xe9"\n', "not UTF-8 text: byte 0xe9 at offset 12 (line 1, "
                                            "column 13)"),
    ("Latin-1 after a UTF-8 BOM", b'\xef\xbb\xbftitle = "caf\xe9"\n',
     "not UTF-8 text: byte 0xe9 at offset 15 (line 1, column 16)"),
    ("UTF-16", BASE.encode("utf-16"), "UTF-16 text (byte order mark at offset 0); expected UTF-8"),
    ("missing file", None, "cannot read the scene file (No such file or directory)"),
    ("invalid TOML", b'title = "x"\nelements = = 10\n', "TOML syntax error: "),
    ("empty file", b"", "the scene file is empty"),
    ("only comments", b"# nothing\n\n", "the scene file is empty"),
    ("nested too deeply", ("a = " + "[" * 5000 + "]" * 5000).encode(), "nested too deeply"),
    ("an integer of 5000 digits", ("a = 1" + "0" * 5000).encode(),
     "an integer with too many digits"),
    ("oversized file", b"#" * (16 * 2**20 + 1), "expected a scene file of at most 16 MiB"),
]


@pytest.mark.parametrize("description, content, message", FILE_CASES,
                         ids=[c[0] for c in FILE_CASES])
def test_bad_scene_file_is_a_scene_error_naming_the_file(tmp_path, description, content,
                                                         message):
    path = _write(tmp_path, content)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    text = str(info.value)
    assert text.startswith(f"{path}: "), text
    assert message in text
    if description == "invalid TOML":
        assert "line 2," in text


def test_directory_and_device_are_not_scene_files(tmp_path):
    with pytest.raises(SceneError, match=f"^{tmp_path}: is a directory; expected a scene file"):
        load_scene(tmp_path)
    with pytest.raises(SceneError, match="^/dev/null: not a regular file"):
        load_scene("/dev/null")


def test_utf8_byte_order_mark_is_skipped(tmp_path):
    path = _write(tmp_path, b"\xef\xbb\xbf" + BASE.encode())
    assert load_scene(path).bodies[0].name == "beam"


# --------------------------------------------------------------------------- random corpus

ODD_VALUES = [0, -1, 10**400, -0.0, 1e-320, 1e308, math.nan, -math.inf, True, "", " ", "x" * 300,
              "a\x00b", "beam:\u0663", "beam:-1", [], [0, 0], [1e308] * 3, [[0, 1], [0, 1]], {},
              {"type": "table", "points": []}, datetime.date(2020, 1, 1), [[[]]], 0.5, 1e-3]


def _mutated(rng: random.Random) -> dict:
    """BASE with one to three leaves replaced by odd values or deleted."""
    data = tomllib.loads(rng.choice([BASE, BASE_2D]))

    def paths(obj, path=()):
        items = obj.items() if isinstance(obj, dict) else \
            enumerate(obj) if isinstance(obj, list) else ()
        for key, value in items:
            yield (*path, key)
            yield from paths(value, (*path, key))

    for _ in range(rng.randint(1, 3)):
        *parents, last = rng.choice(list(paths(data)))
        target = data
        for key in parents:
            target = target[key]
        if isinstance(target, dict) and rng.random() < 0.2:
            del target[last]
        else:
            target[last] = copy.deepcopy(rng.choice(ODD_VALUES))
    return data


def test_random_malformed_scenes_raise_only_one_line_scene_errors():
    rng = random.Random(10)
    errors = 0
    for _ in range(400):
        data = _mutated(rng)
        try:
            parse_scene(data)
        except SceneError as error:
            errors += 1
            assert "\n" not in str(error) and len(str(error)) < 1000
    assert errors > 300


# --------------------------------------------------------------------------- mesh files

def _strip(cell: str = "quad8", bend: float = 0.0, flip: bool = False, extra=(),
           turn: bool = False, squash: bool = False):
    """A 2 x 1 strip of ``cell`` cells (quad8 or quad) on [0, 2] x [0, 1], bent about the y
    axis by ``bend`` (z = bend x^2), its second cell numbered the other way round if
    ``flip``, from another corner if ``turn``, squashed to a line if ``squash``; 0/1 point
    data sets ``clamped`` (x = 0), ``none`` (empty); ``extra`` blocks."""
    import meshio

    quad8 = cell == "quad8"
    nodes = [(x / 2, y / 2) for y in range(3) for x in range(5)] if quad8 else \
        [(x, y) for y in range(2) for x in range(3)]
    index = {p: k for k, p in enumerate(nodes)}
    cells = []
    for i in range(2):
        corners = [(i, 0), (i + 1, 0), (i + 1, 1), (i, 1)]
        mids = [(i + 0.5, 0), (i + 1, 0.5), (i + 0.5, 1), (i, 0.5)]
        cells.append([index[p] for p in corners + (mids if quad8 else [])])
    if turn:
        c = cells[1]
        cells[1] = c[1:4] + c[:1] + (c[5:8] + c[4:5] if quad8 else [])
    if flip:
        c = cells[1]
        cells[1] = [c[0], c[3], c[2], c[1]] + ([c[7], c[6], c[5], c[4]] if quad8 else [])
    points = np.array([(x, y * (x <= 1 or not squash), bend * x * x) for x, y in nodes])
    return meshio.Mesh(points, [(cell, np.array(cells)), *extra], point_data={
        "clamped": np.isclose(points[:, 0], 0).astype(np.int32),
        "none": np.zeros(len(points), np.int32)})


def _chain(branch: bool = False, twin: bool = False):
    import meshio

    points = np.array([(0, 0, 0), (1, 0, 0), (1 + (not twin), 0, 0), (1, 1, 0)], float)
    cells = [[0, 1], [1, 2]] + ([[1, 3]] if branch else [])
    return meshio.Mesh(points if branch else points + [0, 0, 0.5], [("line", np.array(cells))])


SHELL_MESH = 'element = "shell3d_3833"\nsection = { thickness = 0.01 }\nmesh = { file = "m.vtu" }\n'
PLATE_MESH = 'element = "plate3d"\nsection = { thickness = 0.01 }\nmesh = { file = "m.vtu" }\n'
CLAMP_SET = '[[constraint]]\ntype = "clamp"\nedge = "b:clamped"\n'
MESH_CASES = [
    ("missing mesh file", None, SHELL_MESH, CLAMP_SET, 'body[0].mesh.file: no mesh file "m.vtu"'),
    ("unreadable mesh file", b"<VTKFile garbage", SHELL_MESH, CLAMP_SET,
     'body[0].mesh.file: "m.vtu": cannot read the mesh'),
    ("no cells of the kind's dimension", lambda: _chain(), SHELL_MESH, "",
     "body[0].mesh.file: \"m.vtu\": no cells of a usable type: shell3d_3833 takes quad8 "
     "cells"),
    ("cells of another layout", lambda: _strip("quad"), SHELL_MESH, CLAMP_SET,
     'body[0].mesh.file: "m.vtu": quad cells do not fit shell3d_3833: shell3d_3833 takes '
     "quad8 cells"),
    ("mixed cell types", lambda: _strip(extra=[("quad", np.array([[0, 1, 6, 5]]))]), SHELL_MESH,
     CLAMP_SET, 'body[0].mesh.file: "m.vtu": mixed cell types quad, quad8'),
    ("cells of opposite orientations", lambda: _strip(flip=True), SHELL_MESH, CLAMP_SET,
     'body[0].mesh.file: "m.vtu": elements 0, 1 meet at node 2 with opposite orientations'),
    ("a curved plate3d mesh", lambda: _strip("quad", bend=0.05), PLATE_MESH, CLAMP_SET,
     'body[0].mesh.file: "m.vtu": plate3d nodes carry r_x and r_y, which every element sharing '
     "a node uses as its own"),
    ("a plate3d cell numbered from another corner", lambda: _strip("quad", turn=True),
     PLATE_MESH, CLAMP_SET, 'body[0].mesh.file: "m.vtu": plate3d nodes carry r_x and r_y, '
     "which every element sharing a node uses as its own: elements meeting at a slope or with "
     "turned sides would need a transformation of the gradients between them (the slope "
     "discontinuity of Shabana and Mikkola), so a plate3d mesh must be flat rectangles with "
     "one common frame, and element 1 is not a rectangle with sides parallel to element 0's"),
    ("a degenerate cell", lambda: _strip(bend=0.0, squash=True), SHELL_MESH, CLAMP_SET,
     'body[0].mesh.file: "m.vtu": element 1 degenerates at its node'),
    ("two nodes of a line at one point", lambda: _chain(twin=True),
     'element = "beam3d"\nsection = { height = 0.1, width = 0.1 }\nmesh = { file = "m.vtu" }\n',
     "", 'body[0].mesh.file: "m.vtu": nodes 1 and 2 of the chain lie at one point'),
    ("unknown set", lambda: _strip(), SHELL_MESH, CLAMP_SET.replace("b:clamped", "b:clampd"),
     'constraint[0].edge: body "b" (meshed from a file) has no node set "clampd"'),
    ("a set naming no nodes", lambda: _strip(), SHELL_MESH,
     CLAMP_SET.replace("b:clamped", "b:none"),
     'constraint[0].edge: set "none" of body "b" names no node of the body'),
    ("a set of several nodes as a node", lambda: _strip(), SHELL_MESH,
     '[[load]]\ntype = "point_force"\nnode = "b:clamped"\nforce = [0.0, 0.0, 1.0]\n',
     'load[0].node: set "clamped" of body "b" holds 3 nodes; a node reference names one'),
    ("a line moment on a set", lambda: _strip("quad"), PLATE_MESH,
     CLAMP_SET.replace('"clamp"', '"pin"') + '[[load]]\ntype = "line_moment"\n'
     'edge = "b:clamped"\nmoment_per_length = [0.0, 1.0, 0.0]\n',
     "load[0].edge: b:clamped is a node set of a mesh file; a line moment acts along a grid "
     "line of a rectangle body"),
    ("a mesh and a placement", lambda: _strip(),
     SHELL_MESH + 'rectangle = { corner = [0.0, 0.0, 0.0], size = [1.0, 1.0], grid = [1, 1] }\n',
     CLAMP_SET, "body[0].rectangle: the mesh file sets the body's placement"),
    ("line cells for a 3-node beam", lambda: _chain(),
     'element = "beam3d_3node"\nsection = { height = 0.1, width = 0.1 }\n'
     'mesh = { file = "m.vtu" }\n', "", 'body[0].mesh.file: "m.vtu": line cells do not fit '
     "beam3d_3node: beam3d_3node takes line3 cells (its 3 nodes at (0), (1), (0.5) of the "
     "cell, in meshio's order)"),
    ("a 2D beam off the plane", lambda: _chain(),
     'element = "beam2d"\nsection = { height = 0.1, width = 0.1 }\nmesh = { file = "m.vtu" }\n',
     "", 'body[0].mesh.file: "m.vtu": beam2d is 2D; expected points at z = 0'),
    ("a branching chain of beams", lambda: _chain(branch=True),
     'element = "beam3d"\nsection = { height = 0.1, width = 0.1 }\nmesh = { file = "m.vtu" }\n',
     "", 'body[0].mesh.file: "m.vtu": node 1 joins 3 elements; a line body is one chain'),
]


@pytest.mark.parametrize("description, mesh, body, rest, message", MESH_CASES,
                         ids=[c[0] for c in MESH_CASES])
def test_bad_mesh_file_is_a_scene_error_naming_the_key(tmp_path, description, mesh, body,
                                                       rest, message):
    import meshio

    if callable(mesh):
        meshio.write(tmp_path / "m.vtu", mesh())
    elif mesh is not None:
        (tmp_path / "m.vtu").write_bytes(mesh)
    path = _write(tmp_path, '[material.steel]\nE = 2.1e11\nnu = 0.3\nrho = 7800.0\n'
                  f'[[body]]\nname = "b"\nmaterial = "steel"\n{body}\n{rest}\n'
                  "[analysis.static]\n")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    text = str(info.value)
    assert text.startswith(message.split(":")[0] + ":"), text
    assert message in text, text
