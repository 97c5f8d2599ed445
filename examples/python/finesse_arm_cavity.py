"""An aLIGO arm cavity in Finesse 3 with two pendkit quad-aligo suspensions: the hard and
soft pitch modes at several circulating powers, by three routes.

- ``finesse_pendkit_hz``: Finesse 3 solves the arm (HG modes to order 1, radiation
  pressure) with ``pendkit.finesse.suspension`` plants on the ITM and ETM; a resonance is
  where Re(1/H) of the ETM's torque-to-pitch response H falls through zero.
- ``scene_hz``: pendkit's own scene ``arm-cavity`` at the same power (the optical-spring
  element, Sidles & Sigg), as ``pendkit modes arm-cavity --set power=P`` prints it; hard and
  soft are the modes whose test-mass pitch lies most along the optical spring's
  eigenvectors.
- ``closed_form_hz``: Sidles-Sigg's hard/soft stiffness k = (2PL/c)/(1 - g1 g2) x the
  eigenvalues of [[-g2, 1], [1, -g1]] added to one quad's test-mass pitch stiffness: where
  Re(1/h) + k falls through zero, h pendkit's single-quad torque-to-pitch response.
- ``finesse_ligo_hz`` (with finesse-ligo installed): the Finesse route with finesse-ligo
  1.0.15's damped quad ZPK (its QUADSuspension data) instead of pendkit's plant.

Arm: L = 3994.5 m, ITM T = 0.014, Rc 1934 m, ETM T = 5e-6, Rc 2245 m (finesse-ligo's
aligo.kat). Needs finesse==3.0.2 (Python >= 3.10) and pendkit:

    python examples/python/finesse_arm_cavity.py [--powers 1e5,3e5,4e5]
"""

import argparse
import importlib.util
import os

import numpy as np

import finesse
from finesse.analysis.actions import FrequencyResponse
from finesse.components.mechanical import SuspensionZPK

import pendkit
import pendkit.finesse

LENGTH, ROC_ITM, ROC_ETM = 3994.5, 1934.0, 2245.0  # m
C = 299_792_458.0  # m/s
G1, G2 = 1 - LENGTH / ROC_ITM, 1 - LENGTH / ROC_ETM
GRID = np.geomspace(0.05, 5.0, 1200)  # Hz

ARM = f"""
l L0 P=1
s s0 L0.p1 ITM.p1
m ITM T=0.014 L=0 Rc=-{ROC_ITM}
s LX ITM.p2 ETM.p1 L={LENGTH}
m ETM T=5e-6 L=0 Rc={ROC_ETM}
cav XARM ITM.p2
pd Pcirc ETM.p1.i
modes(maxtem=1)
fsig(1)
"""


def arm(suspend):
    model = finesse.Model()
    model.parse(ARM)
    suspend(model)
    return model, float(model.run("noxaxis()")["Pcirc"])  # circulating W per input W


def falling_zeros(f, y):
    i = np.nonzero((y[:-1] > 0) & (y[1:] <= 0))[0]
    return f[i] - y[i] * (f[i + 1] - f[i]) / (y[i + 1] - y[i])


def finesse_resonances(model, gain, power):
    model.L0.P = power / gain
    out = model.run(FrequencyResponse(GRID, [model.ETM.mech.F_pitch], [model.ETM.mech.pitch]))
    return falling_zeros(GRID, np.real(1 / out.out[:, 0, 0]))


def spring_constants(power):
    k = 2 * power * LENGTH / C / (1 - G1 * G2) * np.array([[-G2, 1.0], [1.0, -G1]])
    values, vectors = np.linalg.eigh(k)
    return [(values[1], vectors[:, 1]), (values[0], vectors[:, 0])]  # hard, soft


def nearest(values, target):
    values = np.asarray(values)
    return float(values[np.argmin(np.abs(values - target))]) if len(values) else float("nan")


def ligo_plant():
    """finesse-ligo's damped quad L3 torque-to-pitch ZPK, or None (finesse_ligo 1.0.15
    does not import with Finesse 3.0.2, so its data file is read directly)."""
    spec = importlib.util.find_spec("finesse_ligo")
    if spec is None or not spec.submodule_search_locations:
        return None
    import h5py

    path = os.path.join(spec.submodule_search_locations[0], "data", "suspensions",
                        "quad_damped_zpk.h5")
    with h5py.File(path, "r") as data:
        g = data["damped/zpk"]["L3.disp.P"]["L3.drive.P"]
        return g["z"][:], g["p"][:], float(g["k"][()])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--powers", default="1e5,2e5,3e5,4e5",
                        help="circulating powers, W (comma-separated)")
    args = parser.parse_args()
    powers = [float(p) for p in args.powers.split(",")]

    quad = pendkit.Model("quad-aligo").run()

    def with_pendkit(model):
        for name in ("ITM", "ETM"):
            model.add(pendkit.finesse.suspension(quad, getattr(model, name), p1_normal="-x"))

    pk_model, pk_gain = arm(with_pendkit)
    zpk = ligo_plant()
    if zpk is not None:
        def with_ligo(model):
            for name in ("ITM", "ETM"):
                model.add(SuspensionZPK(f"{name}_sus", getattr(model, name).mech,
                                        {("pitch", "F_pitch"): zpk}))

        ligo_model, ligo_gain = arm(with_ligo)
    h = quad.tf("force:pitch3", "pitch3", GRID)

    print("power_w,mode,finesse_pendkit_hz,scene_hz,closed_form_hz,finesse_ligo_hz")
    for power in powers:
        found = finesse_resonances(pk_model, pk_gain, power)
        ligo = finesse_resonances(ligo_model, ligo_gain, power) if zpk is not None else []
        modes = pendkit.Model("arm-cavity", set={"power": power}).run().modes()
        cols = [modes.coordinates.index("itm_pitch3"), modes.coordinates.index("etm_pitch3")]
        for name, (k, vector) in zip(("hard", "soft"), spring_constants(power)):
            scene = modes.frequencies[np.argmax((modes.shapes[:, cols] @ vector) ** 2)]
            closed = nearest(falling_zeros(GRID, np.real(1 / h) + k), scene)
            print(f"{power:g},{name},{nearest(found, scene):.6f},{scene:.6f},{closed:.6f},"
                  f"{nearest(ligo, closed):.6f}")


if __name__ == "__main__":
    main()
