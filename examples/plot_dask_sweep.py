"""
A sweep on a Dask cluster
=========================

A bifurcation diagram by sweeps (:func:`fempipe.compute_bifurcation_diagram`) integrates at each flow
velocity until the motion settles, starting from the previous point's attractor; the sweeps
up and down in v (and for several inclinations) are independent and run on any
:class:`concurrent.futures.Executor`.  Dask's ``Client.get_executor()`` is one: on the
command line, ``fempipe bifurcation --dask tcp://host:port`` (needs ``fempipe[dask]``).
Here a one-worker, one-thread :class:`dask.distributed.LocalCluster` inside this process
stands in for a real cluster; with a remote cluster the point store (``store_dir``) must be
a directory the workers can see.
"""

# %%
# The cluster and the sweeps
# --------------------------
import shutil
import tempfile

import matplotlib.pyplot as plt
import numpy as np
from dask.distributed import Client, LocalCluster

import fempipe
from fempipe.plotting.scripts import show_or_save

model = fempipe.PipeModel(fempipe.Modal(3), fempipe.Params(alpha=0.0))  # the paper's pipe
flows = [6.0, 6.8]
store = tempfile.mkdtemp(prefix="fempipe-dask-")
with (
    LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster,
    Client(cluster) as client,
):
    diagram = fempipe.compute_bifurcation_diagram(
        model,
        flows,
        ("up", "down"),
        store_dir=store,
        executor=client.get_executor(),
        t_max=150.0,
    )
for p in diagram.points:
    amp = 0.5 * (p["eta_tip"][1] - p["eta_tip"][0])
    print(
        f"{p['direction']:4s} v = {p['v']:.1f}: {p['attractor']:11s} amplitude eta(1) = {amp:.5f}"
    )
shutil.rmtree(store)  # the point store (it lets an interrupted diagram resume)
onset = min(p["v"] for p in diagram.points if p["attractor"] == "periodic")

#: the smallest swept v with a periodic attractor (checked against the classical v_cr)
RESULT = onset

# %%
# The diagram
# -----------
# Below v_cr (6.33 for this pipe) the sweeps settle on the equilibrium, above it on the
# flutter limit cycle; up and down agree, as they should where there is no hysteresis.
fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
for direction, marker in (("up", "o"), ("down", "x")):
    pts = [p for p in diagram.points if p["direction"] == direction]
    amp = [0.5 * (p["eta_tip"][1] - p["eta_tip"][0]) for p in pts]
    ax.plot([p["v"] for p in pts], amp, marker, label=f"sweep {direction}")
ax.set_xlabel("v")
ax.set_ylabel("amplitude of eta(1)")
ax.set_title("alpha = 0, beta = 0.142, gamma = 18.9, mu = 5e-3; N = 3 sine modes", fontsize=9)
ax.legend(fontsize=8)
np.testing.assert_equal(len(diagram.points), 2 * len(flows))
show_or_save()  # run as a script: a window, or PNG files without a display
