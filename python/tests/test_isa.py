"""RAYLAB_ISA: every instruction set this CPU has answers the same, bit for bit; a wrong one
stops the import with its reason."""

import os
import subprocess
import sys

import numpy as np

import raylab

SETS = ["scalar", "sse2", "avx2", "avx512"]

# Random rays at a random triangle soup, answered under the set RAYLAB_ISA names: prints the
# set, a digest of every answer's bytes, and how many rays hit and are blocked.
SCRIPT = """
import hashlib, sys, numpy as np, raylab
rng = np.random.default_rng(5)
v = rng.random((3000, 3), dtype=np.float32)
f = rng.integers(0, 3000, (2000, 3))
f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
mesh = raylab.Mesh(v, f)
o = rng.random((20000, 3), dtype=np.float32) * 3 - 1
d = rng.random((20000, 3), dtype=np.float32) - 0.5
hits = mesh.intersect(o, d)
blocked = mesh.occluded(o, d, t_max=0.7)
print(raylab.ISA)
answers = (hits.t, hits.triangle, hits.u, hits.v, blocked)
print(hashlib.sha256(b"".join(a.tobytes() for a in answers)).hexdigest())
print(int((hits.triangle >= 0).sum()), int(blocked.sum()))
"""


def run(isa):
    env = dict(os.environ, RAYLAB_ISA=isa)
    return subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True)


def test_the_set_in_use_is_named():
    assert raylab.ISA in SETS


def test_every_supported_set_answers_the_same():
    answers = {}
    for isa in SETS:
        done = run(isa)
        if done.returncode != 0:
            # A set this CPU lacks is refused by name; the portable ones never are.
            assert isa in ("avx2", "avx512"), done.stderr
            assert f"this CPU cannot run {isa}" in done.stderr, done.stderr
            continue
        name, digest, counts = done.stdout.split("\n")[:3]
        assert name == isa
        hits, blocked = map(int, counts.split())
        assert hits > 1000 and blocked > 500, counts
        answers[isa] = (digest, counts)
    assert len(answers) >= 2
    assert len(set(answers.values())) == 1, answers


def test_an_unknown_set_stops_the_import():
    done = run("avx3")
    assert done.returncode != 0
    assert "RAYLAB_ISA: unknown instruction set 'avx3'" in done.stderr, done.stderr
