"""pygwinc 0.6.2's suspension thermal noise and resonances for aLIGO, printed as JSON.

Usage: python pygwinc_quad_aligo.py FREQS [--massless-fibres]
  FREQS: comma-separated frequencies (Hz).
Prints {"version", "theta", "asd": [...], "horizontal": [...], "vertical": [...]} with the
ASD (m/rtHz) of the test mass along the beam, pygwinc's total suspension thermal noise
(sum of the horizontal joints and theta^2 times the vertical ones), and the resonance
frequencies (Hz) of its horizontal and vertical 4-mass chains, found as the peaks of the
top-to-test-mass transfer functions (hTable, vTable).
--massless-fibres sets the fibre density to ~0 in pygwinc's continuum fibre springs only
(not in the thermoelastic loss), to measure the fibre-mass (violin) effect that pendkit's
massless effective fibre leaves out.
"""
import json
import sys

import numpy as np
import gwinc
import gwinc.suspension as susp
from gwinc.noise.suspensionthermal import suspension_thermal


def main():
    freqs = np.array([float(x) for x in sys.argv[1].split(",")])
    if "--massless-fibres" in sys.argv[2:]:
        kh, kv = susp.continuumWireKh, susp.continuumWireKv

        def kh_light(w, N, length, tension, xsect, xII, rho, Y, phi):
            return kh(w, N, length, tension, xsect, xII, rho * 1e-9, Y, phi)

        def kv_light(w, N, length, xsect, xsectEnd, rho, Y, phi, **kw):
            return kv(w, N, length, xsect, xsectEnd, rho * 1e-9, Y, phi, **kw)

        susp.continuumWireKh, susp.continuumWireKv = kh_light, kv_light
    ifo = gwinc.load_budget("aLIGO").ifo
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
