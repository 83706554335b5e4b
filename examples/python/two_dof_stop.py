"""A 2-DOF system with a stop: trace its response curve with wbm and plot it with matplotlib.

Two masses in a chain (x1 forced, x2 against a stiff stop at 1 mm), harmonic balance with
continuation in frequency and Floquet stability. From a build tree:

    PYTHONPATH=build/python python3 examples/python/two_dof_stop.py [output.png]

(or without PYTHONPATH after `cmake --install`, which puts the module in site-packages).
"""
import sys

import matplotlib

matplotlib.use("Agg")  # write a file; no display needed
import matplotlib.pyplot as plt
import numpy as np

import wbm

scene = {
    "structure": {
        "mass": [[1.0, 0.0], [0.0, 0.5]],                  # kg
        "stiffness": [[6e4, -2e4], [-2e4, 2e4]],           # N/m
        "dofs": ["x1", "x2"],
    },
    "damping": {"alpha": 4.0},                             # C = αM [1/s]
    "forcing": {"amplitude": 20.0, "frequency_hz": [15.0, 45.0], "dof": "x1"},
    "contact": {"law": "linear", "stiffness": 1e6, "gap": 1e-3, "dof": "x2"},
    "analysis": {"type": "continuation"},                  # pseudo-arclength + Floquet
}

result = wbm.run_scene(scene)
print(result["summary"])
if not result["converged"]:
    sys.exit("the branch did not reach the range: " + str(result["diagnostics"].get("status")))
branch = result["tables"]["branch.csv"]
f = branch["frequency [Hz]"]
amplitude = branch["amplitude_x1 [m]"] * 1e3
stable = branch["stable [-]"] == 1.0

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(f, np.where(stable, amplitude, np.nan), "C0-", label="stable")
ax.plot(f, np.where(stable, np.nan, amplitude), "C3--", label="unstable")
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel("amplitude of x1 [mm]")
ax.set_title("2-DOF chain against a stop at 1 mm (x2)")
ax.legend()
fig.tight_layout()
out = sys.argv[1] if len(sys.argv) > 1 else "two_dof_stop.png"
fig.savefig(out, dpi=120)
print("wrote", out)
