"""Repository locations shared by the harness (everything is relative to the repo root)."""
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
VERIFICATION = REPO / "verification"
CASES = VERIFICATION / "cases"
FENICSX = REPO / "references" / "fenicsx"
FENICSX_RESULTS = FENICSX / "results"
BASELINE = REPO / "references" / "baseline.json"
DEFAULT_QDEMSPH = REPO / "build" / "bin" / "qdemsph"
DEFAULT_OUT = REPO / "build" / "verify"

# meshio41 (mesh reading, face means) lives beside the FEniCSx scripts and needs only numpy.
if str(FENICSX) not in sys.path:
    sys.path.insert(0, str(FENICSX))
