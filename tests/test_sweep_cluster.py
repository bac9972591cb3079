"""A sweep on a multi-node Ray cluster (a head and a worker node on loopback, one CPU each, no GPU): its cells run
on both nodes and their results are gathered in one sweep folder; cells asking for a GPU are refused in one line."""

import json

import pandas as pd
import pytest
import ray
import yaml
from ray.cluster_utils import Cluster

from lerobot_contrast.sweep.command import main

SPEC = {
    "eval": {"n_instances": 3, "max_episode_steps": 30, "rerun": False, "policy": {"type": "oracle"}},
    "grid": {"seed": [0, 1, 2, 3]},
}


@pytest.mark.slow
def test_cells_spread_over_the_nodes_of_a_cluster_and_their_results_are_gathered(tmp_path, capsys):
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "num_gpus": 0, "include_dashboard": False})
    cluster.add_node(num_cpus=1, num_gpus=0)
    try:
        cluster.wait_for_nodes()
        ray.init(address=cluster.address, log_to_driver=False)
        path, out = tmp_path / "sweep.yaml", tmp_path / "out"
        path.write_text(yaml.safe_dump({**SPEC, "eval": {**SPEC["eval"], "policy.device": "cuda"}}), encoding="utf-8")
        assert main([str(path), f"--output_dir={out}", f"--ray.address={cluster.address}"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: cell seed=0 (and 3 more) runs its policy on cuda and asks Ray for 1 GPU")
        assert "the Ray cluster has no GPU; run the sweep where Ray has GPUs" in err and "\n" not in err
        assert not out.exists()  # refused before anything is written
        path.write_text(yaml.safe_dump(SPEC), encoding="utf-8")
        assert main([str(path), f"--output_dir={out}", f"--ray.address={cluster.address}"]) == 0
        cells = json.loads((out / "sweep.json").read_text())["cells"]
        nodes = {node["NodeID"] for node in ray.nodes() if node["Alive"]}
        assert len(nodes) == 2 and {cell["node"] for cell in cells} == nodes
        results = pd.read_parquet(out / "results.parquet")
        assert sorted(set(results["cell"])) == [f"seed={s}" for s in range(4)]
        assert results.groupby("cell").size().to_dict() == {cell["name"]: cell["trials"] for cell in cells}
    finally:
        ray.shutdown()
        cluster.shutdown()


def test_a_head_that_cannot_start_a_client_server_is_tried_again_then_named_in_one_line(monkeypatch):
    from lerobot_contrast.sweep import cluster as joining
    from lerobot_contrast.sweep.settings import RayArgs

    failure = "Initialization failure from server:\nTraceback ...\nRuntimeError: Starting Ray client server failed."
    tries, failing = [], {"times": 2}

    def init(**kwargs):
        tries.append(kwargs["address"])
        if len(tries) <= failing["times"]:
            raise ConnectionAbortedError(failure)

    monkeypatch.setattr(joining, "reach", lambda given: "head:10001")
    monkeypatch.setattr(joining, "runtime_env", lambda: {})
    monkeypatch.setattr(joining, "CLIENT_RETRY_S", 0.0)
    monkeypatch.setattr(joining.ray, "init", init)
    monkeypatch.setattr(joining.ray, "shutdown", lambda: None)
    monkeypatch.setattr(joining.ray, "is_initialized", lambda: False)
    joining.join(RayArgs(address="ray://head:10001"))
    assert tries == ["ray://head:10001"] * 3  # two failed starts, then joined

    tries.clear()
    failing["times"] = joining.CLIENT_START_TRIES
    with pytest.raises(joining.ClusterError) as error:
        joining.join(RayArgs(address="ray://head:10001"))
    assert len(tries) == joining.CLIENT_START_TRIES
    assert str(error.value).startswith("--ray.address=ray://head:10001: cannot join (Initialization failure")
    assert "Starting Ray client server failed" in str(error.value) and "\n" not in str(error.value)
