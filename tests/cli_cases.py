"""Data and options shared by the command-line tests."""

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HEATING = ROOT / "data" / "heating_system" / "heating_system.csv"

# A step test of 40 rows at 1 s: the input steps at 6 s, the output at 7 s.
GOOD = "time,u,y\n" + "".join(f"{t},{1.0 if t > 5 else 0.0},{2.0 if t > 6 else 0.0}\n" for t in range(40))
BASE = (
    "--time time --input u --output y --model first-order --param K=0:5 --param T=0:5 --samples 100 --n 3 --seed 2"
).split()
