"""
A user's CSV through ``compare``
================================

You have numbers from your own code (a modal code, another FE code, an experiment) and want
to know whether they differ from fempipe by more than fempipe's own discretization error.
``fempipe compare FILE.csv`` reads one case per row, computes each quantity on a
discretization and on its refinement, and says a value *differs* when the difference exceeds the
error estimate (a Grid Convergence Index), *agrees* otherwise; the exit status is 0 only when
every value agrees, as diff's.  The library form is :func:`fempipe.compare_values`.
Here the "user" is the paper's method, three sine modes (Eq. (22)).
"""

# %%
# The file
# --------
# A header with the columns (units in brackets optional), a comment line saying where the
# numbers come from, then one case per row.  Everything is written into a temporary directory.
import contextlib
import io
import json
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import fempipe
from fempipe.cli import main as fempipe_cli
from fempipe.plotting.scripts import show_or_save

workdir = Path(tempfile.mkdtemp(prefix="fempipe-compare-"))
csv_file = workdir / "mine.csv"
csv_file.write_text(
    "# my code: N = 3 sine modes, as in validation/compare_paper_N3.csv\n"
    "# (beta = 0.142 and mu = 5e-3 are fempipe's defaults)\n"
    "label,alpha_deg,gamma,v,X_tip [L],theta_tip [rad],v_cr [1]\n"
    "hanging,0,18.9,,,,6.3749331\n"
    "tilted,60,18.9,4,0.86054498,-0.74357232,\n"
)

# %%
# ``fempipe compare`` in this process
# ------------------------------------
# ``--fe P2:8`` keeps it quick (the default is P3:16); ``--json`` prints the contract's keys;
# ``--planar``: the user's code is planar, so its v_cr is compared with fempipe's in-plane one
# (without it, v_cr is the first loss of stability in either plane, as ``fempipe critical``'s).
buffer = io.StringIO()
with contextlib.redirect_stdout(buffer):
    status = fempipe_cli(
        ["compare", str(csv_file), "--fe", "P2:8", "--planar", "--json"]
        + ["--out", str(workdir / "out")]
    )
result = json.loads(buffer.getvalue())
print(f"exit status {status}; files written: {sorted(p.name for p in (workdir / 'out').iterdir())}")
for row in result["rows"]:
    print(
        f"{row['label']:8s} {row['quantity']:9s} user {row['user']:.8f} fempipe "
        f"{row['fempipe']:.8f} difference {row['difference']:+.2e} (estimate "
        f"{row['error_estimate']:.1e}): {row['verdict']}"
    )

#: fempipe's v_cr of the hanging pipe on P2:8 (checked against the classical straight-pipe v_cr)
RESULT = next(r["fempipe"] for r in result["rows"] if r["quantity"] == "v_cr")

# %%
# The same through the library, one pair
# --------------------------------------
quantity = fempipe.Quantity("v_cr", fempipe.Params(alpha=0.0), v_max=15.0)
(cmp,) = fempipe.compare_values([(quantity, 6.3749331)], fempipe.FiniteElement(8, 2))
print(f"compare_values: {cmp.to_dict()['fempipe']:.8f}, resolved: {cmp.to_dict()['resolved']}")
shutil.rmtree(workdir)  # the temporary directory and what compare wrote into it

fig, ax = plt.subplots(figsize=(5, 3), layout="constrained")
labels = [f"{r['label']}: {r['quantity']}" for r in result["rows"]]
rel = [abs(r["difference"]) for r in result["rows"]]
est = [r["error_estimate"] for r in result["rows"]]
ax.bar(labels, rel, color="C1", label="|user - fempipe|")
ax.bar(labels, est, color="C0", width=0.4, label="fempipe's error estimate")
ax.set_yscale("log")
ax.set_title("N = 3 sine modes against P2:8 (beta = 0.142, gamma = 18.9)", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display
