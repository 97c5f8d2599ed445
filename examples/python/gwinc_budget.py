"""A pygwinc aLIGO noise budget with pendkit's 3-D quad as its suspension thermal noise.

pygwinc's aLIGO budget computes suspension thermal noise with its own 1-D chain
(``gwinc.noise.suspensionthermal.SuspensionThermal``). This script swaps that term for
:func:`pendkit.gwinc.suspension_thermal` (same inputs and output; four test masses, as
pygwinc counts them), runs both budgets, and prints the suspension term and the total
strain noise of each side by side; ``--plot FILE`` draws pendkit's budget with pygwinc's
plotting.

The drop-in takes the settings of ``ifo.Suspension`` (masses, lengths, fibre geometry,
materials, temperature; a setting it cannot take is an error naming it). The budget runs to
5 kHz, above the fibres' first violin mode (490 Hz), which pendkit's bead-free quad does not
have: the drop-in says so with a ``pendkit.gwinc.ViolinModeWarning`` on stderr, and its
term falls below pygwinc's from about 250 Hz up (``--beads N`` gives the fibres N beads,
and violin modes, at some cost in time).

Needs pygwinc (``pip install gwinc``) and pendkit (``pip install ./crates/interface/python``):

    python examples/python/gwinc_budget.py [--points 1000] [--plot budget.png] [--beads 20]
"""

import argparse

import numpy as np

import gwinc
from gwinc import nb
from gwinc.ifo.aLIGO import aLIGO
from gwinc.noise.suspensionthermal import SuspensionThermal
from gwinc.suspension import precomp_suspension

from pendkit.gwinc import suspension_thermal


class PendkitSuspensionThermal(nb.Noise):
    """Suspension thermal noise of the four test masses, from pendkit's 3-D quad."""

    name = "SuspensionThermal"
    style = dict(label="Suspension Thermal (pendkit quad)", color="#0d75f8")

    sets: list[str] = []  # pendkit overrides after the mapped Suspension settings (--beads)

    @nb.precomp(sustf=precomp_suspension)
    def calc(self, sustf):
        # one suspension's displacement PSD (m²/Hz) times the four test masses of the arms,
        # as pygwinc's SuspensionThermal adds its stages (abs(n) * 4)
        return 4 * suspension_thermal(self.freq, self.ifo.Suspension, sustf, set=self.sets)


class aLIGOWithPendkit(aLIGO):
    """pygwinc's aLIGO budget with pendkit's suspension thermal noise."""

    name = "Advanced LIGO (suspension thermal: pendkit quad)"
    noises = [
        PendkitSuspensionThermal if noise is SuspensionThermal else noise
        for noise in aLIGO.noises
    ]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=1000, help="log-spaced frequencies")
    parser.add_argument("--plot", help="write pendkit's budget figure to this file")
    parser.add_argument("--beads", type=int, default=0,
                        help="violin-mode beads per fibre (pendkit's n_beads; default 0)")
    args = parser.parse_args()
    PendkitSuspensionThermal.sets = [f"n_beads={args.beads}"] if args.beads else []

    freq = np.logspace(np.log10(5.0), np.log10(5000.0), args.points)  # Hz
    reference = gwinc.load_budget("aLIGO", freq=freq)
    budget = aLIGOWithPendkit(freq=freq, ifo=reference.ifo)
    ours, theirs = budget.run(), reference.run()

    print("f_hz,susp_thermal_pygwinc_strain_per_rthz,susp_thermal_pendkit_strain_per_rthz,"
          "total_pygwinc_strain_per_rthz,total_with_pendkit_strain_per_rthz")
    for f_show in [5, 10, 20, 50, 100, 200, 500, 1000]:
        i = int(np.argmin(abs(freq - f_show)))
        print(f"{freq[i]:.4g},{theirs['SuspensionThermal'].asd[i]:.4e},"
              f"{ours['SuspensionThermal'].asd[i]:.4e},{theirs.asd[i]:.4e},{ours.asd[i]:.4e}")
    if args.plot:
        fig = ours.plot()
        fig.savefig(args.plot)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
