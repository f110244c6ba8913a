#!/usr/bin/env python3
"""Paired, interleaved timing of the full solver against Exudyn on the paper's scene.

Usage: scripts/exudyn-compare.sh [--elements 16] [--duration 20] [--repeats 5] [--every 1]
(the shell wrapper makes a venv with `pip install exudyn numpy` and builds host-sim).

Both sides simulate the same scene from its static equilibrium with the same integrator
(Newmark, beta = 0.36, gamma = 0.7, h = 3 ms, one thread), base 0.5 mm harmonic:

* beam: N ANCF cable elements (Exudyn `ObjectANCFCable2D`, the element of the paper), clamped
  at the base, L = 0.365 m, EA, EI and mass per length from scenes/paper.toml;
* tip mass: a rigid body welded to the beam end A, centre of mass 20.4 mm below A;
* locked ball: a second rigid body welded to the tip (ball centre rho below A);
* free ball: the ball centre held at distance rho from A (`ObjectConnectorDistance`); the
  rolling coupling of the ball's spin, r_b phi = R_tr psi - rho theta, has no ready-made
  Exudyn joint and is replaced by the linear stand-in phi = psi (one scalar constraint, as
  ours): the same unknowns and constraint count, slightly different ball inertia coupling, so
  only the timing is comparable, not the trajectories; the stops are not reached at 3.70 Hz.

Exudyn moves the clamp (absolute coordinates, prescribed base y_b(t) through an offset user
function, initial velocity of the base everywhere); ours works in the frame of the base
(effective gravity g + y_b''). Timed: whole model build, static solve and dynamic run for
Exudyn (in-process, after `import exudyn`); the whole host-sim process (build, static solve,
run, CSV written: every step by default, every n-th with --every; Exudyn writes no solution
file) for ours. Prints the medians and the ratio exudyn / ours per scene.
"""

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time

# scenes/paper.toml
L, MASS, AREA, E, INERTIA = 0.365, 0.116, 4.06e-5, 200e9, 8.47e-12
MT, JT, DT = 0.1154, 1.871e-5, 0.0204
MB, JB, RB, TRACK = 0.014, 3.15e-7, 0.0075, 0.0395
RHO = TRACK - RB
G = 9.81
AMP = 0.5e-3
BETA, GAMMA, H = 0.36, 0.7, 0.003


def exudyn_run(kind, n, freq, duration, solver, static_q=None):
    import exudyn as exu
    from exudyn.itemInterface import (
        LoadMassProportional,
        MarkerBodyMass,
        MarkerBodyPosition,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        NodePoint2DSlope1,
        NodePointGround,
        NodeRigidBody2D,
        ObjectANCFCable2D,
        ObjectConnectorCoordinate,
        ObjectConnectorDistance,
        ObjectJointGeneric,
        ObjectRigidBody2D,
    )

    t0 = time.perf_counter()
    w = 2 * math.pi * freq
    v0 = AMP * w  # base velocity at t = 0 (y_b = AMP sin wt): the scene starts at rest on the base
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    le = L / n
    nodes = [
        mbs.AddNode(
            NodePoint2DSlope1(
                referenceCoordinates=[i * le, 0, 1, 0], initialVelocities=[0, v0, 0, 0]
            )
        )
        for i in range(n + 1)
    ]
    elems = []
    for i in range(n):
        elems.append(
            mbs.AddObject(
                ObjectANCFCable2D(
                    nodeNumbers=[nodes[i], nodes[i + 1]],
                    physicsLength=le,
                    physicsMassPerLength=MASS / L,
                    physicsBendingStiffness=E * INERTIA,
                    axialStiffness=E * AREA,
                )
            )
        )
    for e in elems:
        m = mbs.AddMarker(MarkerBodyMass(bodyNumber=e))
        mbs.AddLoad(LoadMassProportional(markerNumber=m, loadVector=[0, -G, 0]))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))

    def base(mbs, t, item, lOffset):
        return AMP * math.sin(w * t)

    for c in range(4):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        if c == 1:
            mbs.AddObject(
                ObjectConnectorCoordinate(markerNumbers=[mg, mc], offsetUserFunction=base)
            )
        else:
            mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mc]))

    def rigid(mass, inertia, pos):
        nd = mbs.AddNode(
            NodeRigidBody2D(referenceCoordinates=[pos[0], pos[1], 0], initialVelocities=[0, v0, 0])
        )
        b = mbs.AddObject(ObjectRigidBody2D(physicsMass=mass, physicsInertia=inertia, nodeNumber=nd))
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=b))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0, -G, 0]))
        return b

    weld = [1, 1, 0, 0, 0, 1]  # planar: x, y and the rotation about z
    end = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[-1], localPosition=[le, 0, 0]))
    tip = rigid(MT, JT, (L, -DT))
    mt_a = mbs.AddMarker(MarkerBodyRigid(bodyNumber=tip, localPosition=[0, DT, 0]))
    mbs.AddObject(ObjectJointGeneric(markerNumbers=[end, mt_a], constrainedAxes=weld))
    ball = rigid(MB, JB, (L, -RHO))
    if kind in ("locked", "static"):
        mb = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ball, localPosition=[0, RHO, 0]))
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[mt_a, mb], constrainedAxes=weld))
    else:
        ma = mbs.AddMarker(MarkerBodyPosition(bodyNumber=tip, localPosition=[0, DT, 0]))
        mbp = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ball, localPosition=[0, 0, 0]))
        mbs.AddObject(ObjectConnectorDistance(markerNumbers=[ma, mbp], distance=RHO))
        # Stand-in for the rolling constraint (one scalar constraint on the spin, as ours):
        # the spin follows the housing, phi = psi.
        spin_t = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.GetObject(tip)["nodeNumber"], coordinate=2))
        spin_b = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.GetObject(ball)["nodeNumber"], coordinate=2))
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[spin_t, spin_b]))
    mbs.Assemble()

    ss = exu.SimulationSettings()
    ss.parallel.numberOfThreads = 1
    ss.linearSolverType = solver
    ss.solutionSettings.writeSolutionToFile = False
    ss.displayComputationTime = False
    ss.displayStatistics = False
    ss.staticSolver.verboseMode = 0
    ss.timeIntegration.verboseMode = 0
    if static_q is None:
        # Static equilibrium at t = 0 (base at y_b(0) = 0), the start of the dynamic run.
        exu.SolveStatic(mbs, ss)
        q = mbs.systemData.GetODE2Coordinates()
    else:
        # Exudyn's static solver finds no start for the hanging ball (no stiffness before the
        # distance constraint carries its weight): the free scene starts from the locked
        # scene's equilibrium (same coordinates, ball plumb below A), solved untimed.
        q = static_q
    mbs.systemData.SetODE2Coordinates(q, configuration=exu.ConfigurationType.Initial)
    static_tip = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Position)[1]
    if kind == "static":
        return q
    ti = ss.timeIntegration
    ti.endTime = duration
    ti.numberOfSteps = int(round(duration / H))
    ti.generalizedAlpha.useNewmark = True
    ti.generalizedAlpha.newmarkBeta = BETA
    ti.generalizedAlpha.newmarkGamma = GAMMA
    ti.generalizedAlpha.useIndex2Constraints = False
    ti.generalizedAlpha.computeInitialAccelerations = True
    ti.newton.relativeTolerance = 1e-5
    exu.SolveDynamic(mbs, ss)
    wall = time.perf_counter() - t0
    tip_y = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Position)[1]
    return wall, (static_tip, tip_y)


def exudyn_static(n, solver):
    """The locked scene's static equilibrium (start of the free scene)."""
    return exudyn_run("static", n, 1.0, 0.0, solver)


def ours_run(binary, kind, n, freq, duration, every=1):
    with tempfile.TemporaryDirectory() as out:
        cmd = [
            binary, "run", "--solver", "full", "--kind", kind, "--elements", str(n),
            "--frequency", str(freq), "--duration", str(duration), "--no-plots", "-o", out,
            "--json", "--every", str(every),
        ]
        t0 = time.perf_counter()
        res = subprocess.run(cmd, check=True, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    json.loads(res.stdout)
    return wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--binary", default="target/release/host-sim")
    ap.add_argument("--elements", type=int, default=16)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--solver", choices=["dense", "sparse"], default="sparse",
                    help="Exudyn linear solver (sparse: the faster of the two at N = 16)")
    ap.add_argument("--every", type=int, default=1,
                    help="ours: write every n-th step to the CSV (default 1, every step; Exudyn "
                    "writes no solution file, so a large value compares the solvers alone)")
    args = ap.parse_args()
    import exudyn as exu

    solver = exu.LinearSolverType.EXUdense if args.solver == "dense" else exu.LinearSolverType.EigenSparse
    print(f"exudyn {exu.__version__}, N = {args.elements}, {args.duration} s simulated, "
          f"{args.repeats} paired runs, Exudyn solver {args.solver}, ours CSV every {args.every}")
    cases = [("free", 3.70), ("locked", 4.13)]
    for kind, f in cases:
        sq = exudyn_static(args.elements, solver) if kind == "free" else None
        ex, us, ratios = [], [], []
        for _ in range(args.repeats):
            # Alternate the order in each pair.
            if len(ex) % 2 == 0:
                a = ours_run(args.binary, kind, args.elements, f, args.duration, args.every)
                b, _ = exudyn_run(kind, args.elements, f, args.duration, solver, sq)
            else:
                b, _ = exudyn_run(kind, args.elements, f, args.duration, solver, sq)
                a = ours_run(args.binary, kind, args.elements, f, args.duration, args.every)
            us.append(a)
            ex.append(b)
            ratios.append(b / a)
        print(f"{kind:6s} {f:.2f} Hz: exudyn {statistics.median(ex):.3f} s, ours "
              f"{statistics.median(us):.3f} s, ratio (median of pairs) "
              f"{statistics.median(ratios):.2f}x  [pairs: {' '.join(f'{r:.2f}' for r in ratios)}]")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
