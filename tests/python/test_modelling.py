"""kccd.fit, kccd.import_urdf, kccd.prove_pairs, Model.with_body_geometry and kccd.explain: equal to
the commands' JSON on the same inputs, checked against oracles of their own (an exact point-to-hull
distance by enumerating faces, point queries at the witnesses), and bad input named."""

import itertools
import json
import pathlib
import re
import subprocess

import numpy as np
import pytest
import yaml

import kccd
from conftest import DATA, ROOT

URDF = ROOT / "tests" / "data" / "urdf"


def hull_distance(p: np.ndarray, core: np.ndarray) -> np.ndarray:
    """Exact distance of points p (S, 3) to conv(core) (K, 3): the closest point lies in the relative
    interior of a face spanned by at most 4 core points, so the smallest distance to the affine
    hulls of all subsets whose projection has non-negative barycentric weights is the distance."""
    best = np.full(len(p), np.inf)
    for size in range(1, min(4, len(core)) + 1):
        for subset in itertools.combinations(range(len(core)), size):
            v = core[list(subset)]
            if size == 1:
                best = np.minimum(best, np.linalg.norm(p - v[0], axis=1))
                continue
            e = (v[1:] - v[0]).T  # (3, size-1)
            g = e.T @ e
            if abs(np.linalg.det(g)) < 1e-18:
                continue
            w = np.linalg.solve(g, e.T @ (p - v[0]).T)  # (size-1, S)
            inside = (w >= -1e-12).all(axis=0) & (w.sum(axis=0) <= 1 + 1e-12)
            d = np.linalg.norm(p - (v[0] + (e @ w).T), axis=1)
            best = np.where(inside, np.minimum(best, d), best)
    return best


def write_stl(path: pathlib.Path, triangles: np.ndarray) -> None:
    lines = ["solid part"]
    for t in triangles:
        lines += ["facet normal 0 0 0", "outer loop", *[f"vertex {x!r} {y!r} {z!r}" for x, y, z in t],
                  "endloop", "endfacet"]
    path.write_text("\n".join(lines + ["endsolid part"]) + "\n")


@pytest.mark.parametrize("k", [1, 3, 6])
def test_fit_covers_every_point(tmp_path: pathlib.Path, k: int) -> None:
    rng = np.random.default_rng(k)
    # A bent bar of random triangles: 0.4 m long, a few cm thick, off the origin.
    s = rng.uniform(0, 1, (60, 3))
    pts = np.stack([0.4 * s[:, 0], 0.03 * s[:, 1] + 0.1 * s[:, 0] ** 2, 0.05 * s[:, 2]], axis=1) + [0.2, -0.1, 0.3]
    tris = pts[rng.integers(0, len(pts), (120, 3))]
    write_stl(tmp_path / "bar.stl", tris)
    seen: list[float] = []
    f = kccd.fit(str(tmp_path / "bar.stl"), k, max_evaluations=600, progress=seen.append)
    assert f["points"].shape == (k, 3) and f["points"].dtype == np.float64
    assert seen and seen == sorted(seen) and seen[-1] == 1.0
    d = hull_distance(tris.reshape(-1, 3), f["points"])
    assert d.max() <= f["radius"], "a vertex of the part lies outside the fitted SSCH"
    assert d.max() >= 0.9 * f["radius"], "the radius is far larger than the part needs"
    assert f["volume"] >= f["hull_volume"] > 0
    assert f["triangles"] == 120


def test_fit_equals_cli(cli) -> None:
    part = DATA / "parts" / "gripper.iv"
    j = json.loads(subprocess.run([str(cli), "fit", str(part), "-k", "4", "--evaluations", "800", "--json"],
                                  check=True, capture_output=True, text=True).stdout)
    f = kccd.fit(str(part), 4, max_evaluations=800)
    assert f["points"].tolist() == j["points"] and f["radius"] == j["radius"]
    assert f["volume"] == j["volume"] and f["hull_volume"] == j["hull_volume"]
    assert f["hull_vertices"] == j["hull_vertices"] and f["evaluations"] == j["evaluations"]
    h = kccd.fit(str(part), exact_hull=True)
    assert len(h["points"]) == h["hull_vertices"] and h["volume"] < f["volume"]


def test_fit_errors(tmp_path: pathlib.Path) -> None:
    with pytest.raises(kccd.InputError) as e:
        kccd.fit(str(tmp_path / "missing.stl"))
    assert "missing.stl" in str(e.value) and e.value.source.endswith("missing.stl")
    bad = tmp_path / "bad.stl"
    bad.write_text("solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                   "endfacet\nendsolid x\n")
    with pytest.raises(kccd.InputError):
        kccd.fit(str(bad))
    for k in (0, 17):
        with pytest.raises(ValueError, match="points"):
            kccd.fit(str(DATA / "parts" / "gripper.iv"), k)

    def stop(_: float) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        kccd.fit(str(DATA / "parts" / "gripper.iv"), 2, progress=stop)


def test_fit_to_a_tolerance_equals_cli_and_holds(cli, tmp_path: pathlib.Path) -> None:
    # A 48-sided cylinder, 4 cm across and 0.25 m long: its hull has 96 vertices.
    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    rim = np.stack([0.02 * np.cos(a), 0.02 * np.sin(a)], axis=1)
    tris = []
    for i in range(48):
        j = (i + 1) % 48
        p0, p1 = rim[i], rim[j]
        tris += [[[*p0, 0], [*p1, 0], [*p1, 0.25]], [[*p0, 0], [*p1, 0.25], [*p0, 0.25]],
                 [[0, 0, 0], [*p1, 0], [*p0, 0]], [[0, 0, 0.25], [*p0, 0.25], [*p1, 0.25]]]
    part = tmp_path / "cyl.stl"
    write_stl(part, np.array(tris))
    f = kccd.fit(str(part), tolerance=0.5, max_evaluations=600)
    j = json.loads(subprocess.run([str(cli), "fit", str(part), "--tolerance", "0.5", "--evaluations", "600", "--json"],
                                  check=True, capture_output=True, text=True).stdout)
    assert f["points"].tolist() == j["points"] and f["radius"] == j["radius"] and f["method"] == j["method"]
    assert f["outside"] == j["outside"] <= 0.5e-3
    assert len(f["points"]) < 96
    verts = np.array(tris).reshape(-1, 3)
    assert hull_distance(verts, f["points"]).max() <= f["radius"], "a vertex lies outside the volume"
    with pytest.raises(ValueError, match="tolerance"):
        kccd.fit(str(part), tolerance=0.0)


def test_import_urdf_to_a_tolerance_equals_cli(cli) -> None:
    args = ["--srdf", str(URDF / "two_link.srdf"), "--package-path", f"kccd_test={URDF}"]
    text = kccd.import_urdf(str(URDF / "two_link.urdf"), srdf=str(URDF / "two_link.srdf"),
                            packages={"kccd_test": str(URDF)}, tolerance=1.0)
    out = subprocess.run([str(cli), "import", str(URDF / "two_link.urdf"), *args, "--tolerance", "1", "-q"],
                         check=True, capture_output=True, text=True).stdout
    assert text == out
    bodies = yaml.safe_load(text)["bodies"]
    assert bodies and all(0 <= float(b["tolerance"]) <= 1e-3 for b in bodies)  # YAML 1.1 reads 1e-06 as text
    with pytest.raises(ValueError, match="pieces"):
        kccd.import_urdf(str(URDF / "two_link.urdf"), pieces="many")


# Each option of `kccd fit` and `kccd import` that shapes the fit has its argument in kccd.fit and
# kccd.import_urdf, under the name the library's checks use, with the same default; the rest shape
# the command line's own output. A new option on either side fails here until the other has it.
FIT_OPTIONS = {"--points": "points", "--part": "part", "--merge": "merge", "--scale": "scale", "--evaluations": "max_evaluations",
               "--seed": "seed", "--hull": "exact_hull", "--tolerance": "tolerance", "--pieces": "pieces",
               "--concavity": "concavity"}
FIT_CLI_ONLY = {"--help", "--name", "--frame", "--model", "--body", "--json", "--quiet"}
IMPORT_OPTIONS = {"--srdf": "srdf", "--points": "points", "--tolerance": "tolerance", "--pieces": "pieces",
                  "--concavity": "concavity", "--margin": "safety_margin", "--package-path": "packages",
                  "--no-visuals": "visuals", "--hulls": "hulls", "--keep-adjacent": "keep_adjacent"}
IMPORT_CLI_ONLY = {"--help", "--output", "--quiet", "--pairs", "--max-boxes"}  # kccd.prove_pairs proves pairs in Python


def cli_options(cli: pathlib.Path, command: str) -> dict[str, str | None]:
    """The long options of `kccd COMMAND --help` and their shown defaults (None: none shown)."""
    text = subprocess.run([str(cli), command, "--help"], check=True, capture_output=True, text=True).stdout
    out: dict[str, str | None] = {}
    for line in text.splitlines():
        m = re.match(r"^\s+(?:-\w,)?(--[\w-]+)(?:,-\w)?(?:\s+\S+?(?:=(\S+))?)?(?:\s|$)", line)
        if m:
            out[m.group(1)] = m.group(2)
    return out


def python_arguments(function) -> dict[str, str]:
    """The arguments of a bound function and their defaults, from its signature line."""
    signature = function.__doc__.splitlines()[0]
    out = {}
    for name, default in re.findall(r"(\w+): [^,=()]+?(?: = ([^,()]+|\[[^]]*\]))?(?=[,)])", signature):
        out[name] = default.strip() if default else ""
    return out


@pytest.mark.parametrize("command,function,options,cli_only", [
    ("fit", kccd.fit, FIT_OPTIONS, FIT_CLI_ONLY), ("import", kccd.import_urdf, IMPORT_OPTIONS, IMPORT_CLI_ONLY)])
def test_every_fit_option_has_its_python_argument(cli, command, function, options, cli_only) -> None:
    shown = cli_options(cli, command)
    assert set(shown) == set(options) | cli_only, f"kccd {command} --help: {sorted(shown)}"
    args = python_arguments(function)
    assert set(options.values()) <= set(args), f"{function.__name__}{sorted(args)}"
    for flag, name in options.items():
        default = shown[flag]
        if default is None or name in ("pieces", "visuals"):
            continue
        assert float(default) == float(args[name].strip("[]").split(",")[0]), f"{flag}={default} but {name}={args[name]}"


def test_fit_request_errors_name_each_front_ends_spelling(cli) -> None:
    gripper = str(DATA / "parts" / "gripper.iv")
    for args, flag, keyword in [(["-k", "17"], "--points", {"points": 17}),
                                (["--pieces", "99"], "--pieces", {"pieces": 99}),
                                (["--pieces", "2", "--concavity", "1e-4"], "--concavity", {"pieces": 2, "concavity": 1e-4})]:
        run = subprocess.run([str(cli), "fit", gripper, *args], capture_output=True, text=True)
        assert run.returncode == 2 and run.stderr.count("\n") == 1 and f"{flag}:" in run.stderr, run.stderr
        name = next(iter(keyword)) if len(keyword) == 1 else "concavity"
        with pytest.raises(ValueError, match=f"^{name}:"):
            kccd.fit(gripper, **{"points": 8, **keyword})


def test_fit_in_pieces_equals_cli(cli, tmp_path: pathlib.Path) -> None:
    # An L of two boxes: concave, it splits into two pieces.
    boxes = []
    for lo, hi in [((0, 0, 0), (0.3, 0.05, 0.05)), ((0, 0, 0), (0.05, 0.3, 0.05))]:
        c = np.array(list(itertools.product(*zip(lo, hi))), dtype=float)
        for a, b, d in [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1), (2, 3, 7), (2, 7, 6), (0, 2, 6),
                        (0, 6, 4), (1, 5, 7), (1, 7, 3)]:
            boxes.append(c[[a, b, d]])
    part = tmp_path / "ell.stl"
    write_stl(part, np.array(boxes))
    f = kccd.fit(str(part), 4, pieces="auto", concavity=10, max_evaluations=300)
    j = json.loads(subprocess.run([str(cli), "fit", str(part), "-k", "4", "--pieces", "auto", "--concavity", "10", "--evaluations", "300",
                                   "--json"], check=True, capture_output=True, text=True).stdout)
    assert len(f["pieces"]) == len(j["pieces"]) >= 2 and f["concavity"] == j["concavity"]
    for a, b in zip(f["pieces"], j["pieces"]):
        assert a["name"] == b["name"] and a["points"].tolist() == b["points"] and a["radius"] == b["radius"]
        assert a["yaml"] == b["yaml"]


def test_with_body_geometry(arm: kccd.Model) -> None:
    f = kccd.fit(str(DATA / "parts" / "gripper.iv"), 2, max_evaluations=300)
    m = arm.with_body_geometry("gripper", f["points"], f["radius"])
    assert m.bodies == arm.bodies and m.source == arm.source and m.yaml != arm.yaml
    assert arm.yaml.count("\n") == m.yaml.count("\n"), "the rest of the text is kept"
    # The gripper is now a different volume: some query must see it.
    c0, c1 = kccd.Checker(arm), kccd.Checker(m)
    q = [0.3, 0.4, 0.6]
    assert c0.query(q, type="distances").distance.tolist() != c1.query(q, type="distances").distance.tolist()
    with pytest.raises(kccd.InputError, match="nothing"):
        arm.with_body_geometry("nothing", f["points"], f["radius"])
    with pytest.raises(ValueError, match="points"):
        arm.with_body_geometry("gripper", np.zeros((2, 2)), 0.1)
    with pytest.raises(ValueError, match="radius"):
        arm.with_body_geometry("gripper", f["points"], float("nan"))


def test_import_urdf_equals_cli(cli) -> None:
    args = dict(srdf=str(URDF / "two_link.srdf"), packages={"kccd_test": str(URDF)}, points=3)
    fractions: list[float] = []
    text = kccd.import_urdf(str(URDF / "two_link.urdf"), progress=fractions.append, **args)  # type: ignore[arg-type]
    out = subprocess.run([str(cli), "import", str(URDF / "two_link.urdf"), "--srdf", args["srdf"], "--package-path",
                          f"kccd_test={URDF}", "-k", "3", "-q"], check=True, capture_output=True, text=True).stdout
    assert text == out
    assert fractions and fractions[-1] == 1.0
    m = kccd.Model.from_yaml(text, "two_link.yaml")
    assert m.state_size > 0 and m.bodies
    with pytest.raises(kccd.InputError, match="kccd_test"):
        kccd.import_urdf(str(URDF / "two_link.urdf"))
    with pytest.raises(ValueError, match="safety_margin"):
        kccd.import_urdf(str(URDF / "two_link.urdf"), safety_margin=-1.0)


def test_prove_pairs_equals_cli_and_holds(cli, arm: kccd.Model) -> None:
    p = kccd.prove_pairs(arm, max_boxes=300)
    j = json.loads(subprocess.run([str(cli), "pairs", str(DATA / "demo_arm.yaml"), "--json", "--max-boxes", "300"],
                                  check=True, capture_output=True, text=True).stdout)
    assert p["margin"] == j["margin"]
    assert [(q["a"], q["b"], q["verdict"], q["boxes"]) for q in p["pairs"]] == \
        [(q["a"], q["b"], q["verdict"], q["boxes"]) for q in j["pairs"]]
    for mine, theirs in zip(p["pairs"], j["pairs"]):
        assert mine["bound"] == theirs.get("bound") and mine["ignore_reason"] == theirs.get("ignore_reason")
    assert [list(e) for e in p["ignore"]] == j["ignore"]
    pruned = p["model"]
    assert set(pruned.pairs) == {(a, b) for a, b in arm.pairs} - {(a, b) for a, b, _ in p["ignore"]}
    # The proofs hold at sampled states: a pair proven never within the margin keeps its distance
    # above the proven bound; a witness is within the margin.
    names = arm.bodies
    checker = kccd.Checker(arm)
    rng = np.random.default_rng(5)
    doc_limits = np.array([j["limits"] for j in yaml.safe_load(arm.yaml)["joints"]])
    never = [q for q in p["pairs"] if q["verdict"] == "never" and (q["a"], q["b"]) in arm.pairs]
    assert never and any(q["verdict"] == "meets" for q in p["pairs"])
    index = {pair: k for k, pair in enumerate(arm.pairs)}
    for state in rng.uniform(doc_limits[:, 0], doc_limits[:, 1], (200, 3)):
        r = checker.query(state, type="distances")
        dist = dict(zip(r.pair.tolist(), r.distance.tolist()))
        for q in never:
            assert dist[index[(q["a"], q["b"])]] >= q["bound"] - 1e-12
    meets = [q for q in p["pairs"] if q["verdict"] == "meets" and (q["a"], q["b"]) in index]
    assert meets, "the arm has checked pairs that meet"
    for q in meets:
        r = checker.query(q["witness_state"], type="distances")
        assert r.distance[r.pair.tolist().index(index[(q["a"], q["b"])])] <= p["margin"]
    assert names == pruned.bodies
    with pytest.raises(ValueError, match="max_boxes"):
        kccd.prove_pairs(arm, max_boxes=0)


def test_explain_equals_cli_and_its_configurations(cli, arm: kccd.Model) -> None:
    lower, upper = [0.3, 0.4, 0.6], [0.5, 1.2, 1.4]
    e = kccd.explain(arm, lower, upper)
    j = json.loads(subprocess.run([str(cli), "query", str(DATA / "demo_arm.yaml"), "--json", "--type", "distances",
                                   "--explain", "--lower", ",".join(map(repr, lower)), "--upper",
                                   ",".join(map(repr, upper))], check=True, capture_output=True, text=True).stdout)
    assert len(e) == len(j["explain"]) > 0
    checker = kccd.Checker(arm)
    for mine, theirs in zip(e, j["explain"]):
        assert (mine["a"], mine["b"], mine["verdict"]) == (theirs["a"], theirs["b"], theirs["verdict"])
        assert mine["bound"] == theirs["bound"] and mine["distance"] == theirs["distance"]
        assert mine["state"].tolist() == [theirs["state"][n] for n in arm.state_names]
        assert mine["point_a"].tolist() == theirs["point_a"]
        # The configuration lies in the box, and a point query there agrees with its distance.
        assert (np.array(lower) <= mine["state"]).all() and (mine["state"] <= np.array(upper)).all()
        r = checker.query(mine["state"], type="distances", exact="all")
        at = r.distance[r.pair.tolist().index(mine["pair"])]
        assert mine["bound"] <= at <= mine["distance"] + 1e-9
        assert mine["distance"] - at < 1e-6
    # A point state: nothing flagged where the query sees no pair within the margin; a real collision where it does.
    assert not checker.query([0.0, -1.2, 0.0]).collision and kccd.explain(arm, [0.0, -1.2, 0.0]) == []
    assert [x["verdict"] for x in kccd.explain(arm, [0.0, 0.0, 0.0])] == ["real"]
    with pytest.raises(ValueError):
        kccd.explain(arm, [0.5, 0.4, 0.6], [0.3, 1.2, 1.4])
    with pytest.raises(ValueError, match="lower"):
        kccd.explain(arm, [0.5, 0.4])
    with pytest.raises(ValueError, match="starts"):
        kccd.explain(arm, lower, upper, starts=0)
