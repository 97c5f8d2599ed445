"""pygwinc 0.6.2's suspension thermal noise and resonances for aLIGO, printed as JSON.

Usage: python pygwinc_quad_aligo.py FREQS [--massless-fibres] [--uniform-fibres]
       python pygwinc_quad_aligo.py --ifo
  FREQS: comma-separated frequencies (Hz).
--ifo prints the numbers of aLIGO's ifo.yaml that quad-aligo takes as its parameters, under
quad-aligo's parameter names, and the stages' centre-of-mass separations (m, top to bottom).
Prints {"version", "theta", "asd": [...], "horizontal": [...], "vertical": [...]} with the
ASD (m/rtHz) of the test mass along the beam, pygwinc's total suspension thermal noise
(sum of the horizontal joints and theta^2 times the vertical ones), and the resonance
frequencies (Hz) of its horizontal and vertical 4-mass chains, found as the peaks of the
top-to-test-mass transfer functions (hTable, vTable).
--massless-fibres sets the fibre density to ~0 in pygwinc's continuum fibre springs only
(not in the thermoelastic loss), to measure the fibre-mass (violin) effect that pendkit's
massless effective fibre leaves out.
--uniform-fibres gives the fibres the middle's radius at the necks too (EndRadius = Radius):
pygwinc's continuum fibres carry the middle's section along their whole length, so with
uniform fibres they are the same fibres as pendkit's beaded ones.
"""
import json
import sys

import numpy as np
import gwinc
import gwinc.suspension as susp
from gwinc.noise.suspensionthermal import suspension_thermal


def ifo_numbers():
    """aLIGO's ifo.yaml `Suspension` (and the arm length) under quad-aligo's names."""
    ifo = gwinc.load_budget("aLIGO").ifo
    s = ifo.Suspension
    # pygwinc numbers the stages from the test mass up; quad-aligo from the top down
    test_mass, pum, uim, top = s.Stage
    out = {
        "version": gwinc.__version__,
        "mn": top.Mass, "m1": uim.Mass, "m2": pum.Mass, "m3": test_mass.Mass,
        "rn": top.WireRadius, "r1": uim.WireRadius, "r2": pum.WireRadius,
        "kv_n": top.K, "kv_1": uim.K, "kv_2": pum.K,
        "blade_n_thickness": top.Blade, "blade_1_thickness": uim.Blade,
        "blade_2_thickness": pum.Blade,
        "l3": test_mass.Length,
        "r3": s.Fiber.Radius, "r3_neck": s.Fiber.EndRadius, "l3_neck": s.Fiber.EndLength,
        "temperature": s.Temp,
        "arm_length": ifo.Infrastructure.Length,
        "silica_rho": s.Silica.Rho, "silica_C": s.Silica.C, "silica_K": s.Silica.K,
        "silica_alpha": s.Silica.Alpha, "silica_dlnE_dT": s.Silica.dlnEdT,
        "silica_phi": s.Silica.Phi, "silica_Y": s.Silica.Y,
        "silica_dissdepth": s.Silica.Dissdepth,
        "steel_rho": s.C70Steel.Rho, "steel_C": s.C70Steel.C, "steel_K": s.C70Steel.K,
        "steel_alpha": s.C70Steel.Alpha, "steel_dlnE_dT": s.C70Steel.dlnEdT,
        "steel_phi": s.C70Steel.Phi, "steel_Y": s.C70Steel.Y,
        "maraging_rho": s.MaragingSteel.Rho, "maraging_C": s.MaragingSteel.C,
        "maraging_K": s.MaragingSteel.K, "maraging_alpha": s.MaragingSteel.Alpha,
        "maraging_dlnE_dT": s.MaragingSteel.dlnEdT, "maraging_phi": s.MaragingSteel.Phi,
        "maraging_Y": s.MaragingSteel.Y,
        "nw": [top.NWires, uim.NWires, pum.NWires, test_mass.NWires],
        # the steel stages' Length is their centre-of-mass separation (ifo.yaml's comment)
        "separations": [top.Length, uim.Length, pum.Length],
    }
    print(json.dumps({k: (float(v) if isinstance(v, (int, float)) else v) for k, v in out.items()}))


def main():
    if "--ifo" in sys.argv[1:]:
        ifo_numbers()
        return
    freqs = np.array([float(x) for x in sys.argv[1].split(",")])
    if "--massless-fibres" in sys.argv[2:]:
        kh, kv = susp.continuumWireKh, susp.continuumWireKv

        def kh_light(w, N, length, tension, xsect, xII, rho, Y, phi):
            return kh(w, N, length, tension, xsect, xII, rho * 1e-9, Y, phi)

        def kv_light(w, N, length, xsect, xsectEnd, rho, Y, phi, **kw):
            return kv(w, N, length, xsect, xsectEnd, rho * 1e-9, Y, phi, **kw)

        susp.continuumWireKh, susp.continuumWireKv = kh_light, kv_light
    ifo = gwinc.load_budget("aLIGO").ifo
    if "--uniform-fibres" in sys.argv[2:]:
        ifo.Suspension.Fiber.EndRadius = ifo.Suspension.Fiber.Radius
    pc = susp.precomp_suspension(freqs, ifo)
    psd = suspension_thermal(freqs, ifo.Suspension, pc)

    # resonances: peaks of |hTable| and |vTable| on a fine grid, refined by a parabola
    grid = np.geomspace(0.2, 20.0, 40001)
    tables = susp.precomp_suspension(grid, ifo)

    def peaks(tf):
        a = np.log(np.abs(tf))
        out = []
        for i in range(1, len(a) - 1):
            if a[i] > a[i - 1] and a[i] >= a[i + 1]:
                # parabola through the three log-spaced points
                d = 0.5 * (a[i - 1] - a[i + 1]) / (a[i - 1] - 2 * a[i] + a[i + 1])
                step = np.log(grid[i + 1] / grid[i])
                out.append(float(grid[i] * np.exp(d * step)))
        return out

    print(json.dumps({
        "version": gwinc.__version__,
        "theta": float(pc.VHCoupling.theta),
        "asd": [float(x) for x in np.sqrt(psd)],
        "horizontal": peaks(tables.hTable),
        "vertical": peaks(tables.vTable),
    }))


main()
