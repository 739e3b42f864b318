"""How Exudyn's explicit DOPRI5 reads the step-size settings (the facts docs/ADAPTIVE.md cites).

Runs one free rigid body (NodeRigidBodyRotVecLG, gravity, tumbling) with
``exu.MainSolverExplicit`` and ``timeIntegration.solverType = DOPRI5`` for several
combinations of ``automaticStepSize``, ``adaptiveStep``, ``numberOfSteps``,
``initialStepSize`` and ``minimumStepSize``; each run in its own process with a time
limit (one combination never returns).  Prints the steps, rejections and the end time.

    python docs/probe_exudyn_adaptive.py
"""
import subprocess
import sys

CASES = [  # automaticStepSize, adaptiveStep, numberOfSteps, initialStepSize, minimumStepSize
    (True, True, 10, 0.0, 1e-8),
    (False, True, 10, 0.0, 1e-8),
    (True, False, 10, 0.0, 1e-8),
    (False, False, 10, 0.0, 1e-8),
    (True, True, 1000, 0.0, 1e-8),
    (True, True, 10, 1e-5, 1e-8),
    (True, True, 10, 0.0, 0.05),
]

CHILD = r"""
import sys, exudyn as exu
from exudyn.utilities import InertiaCuboid
auto, adap, nsteps, hinit, hmin = eval(sys.argv[1])
SC = exu.SystemContainer(); mbs = SC.AddSystem()
mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.3, 0.2, 0.1]), referencePosition=[0, 0, 0],
                    initialAngularVelocity=[3, 1, 7], gravity=[0, 0, -9.81],
                    nodeType=exu.NodeType.RotationRotationVector)
mbs.Assemble()
ss = exu.SimulationSettings(); ti = ss.timeIntegration
ti.endTime = 1.0; ti.numberOfSteps = nsteps; ti.automaticStepSize = auto; ti.adaptiveStep = adap
ti.initialStepSize = hinit; ti.minimumStepSize = hmin
ti.absoluteTolerance = 1e-8; ti.relativeTolerance = 1e-8
ti.solverType = exu.DynamicSolverType.DOPRI5
ss.solutionSettings.writeSolutionToFile = False
solver = exu.MainSolverExplicit(); solver.SolveSystem(mbs, ss); it = solver.it
print(f"steps {it.currentStepIndex - 1}, rejected {it.rejectedAutomaticStepSizeSteps}, "
      f"last step {it.currentStepSize:.3g}, reached t = {it.currentTime:g}")
"""


def main(limit=30.0):
    import exudyn
    print(f"exudyn {exudyn.__version__}, DOPRI5, endTime 1, atol = rtol = 1e-8")
    for case in CASES:
        label = ("automaticStepSize={} adaptiveStep={} numberOfSteps={} initialStepSize={} "
                 "minimumStepSize={}".format(*case))
        try:
            out = subprocess.run([sys.executable, "-W", "ignore", "-c", CHILD, repr(case)],
                                 capture_output=True, text=True, timeout=limit)
            res = out.stdout.strip().splitlines()[-1] if out.stdout.strip() else out.stderr[-200:]
        except subprocess.TimeoutExpired:
            res = f"no return within {limit:g} s (killed)"
        print(f"{label}: {res}")


if __name__ == "__main__":
    main()
