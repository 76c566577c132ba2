"""The Kubernetes manifest of `pedsynth k8s` (issue 16), run by .ci/run.

No cluster runs here, so the manifest is checked in the two ways that do not need one:
1. Every document validates against the Kubernetes OpenAPI schemas (the `kubernetes-validate` package, strict:
   unknown fields are errors) for Kubernetes 1.33 (backoffLimitPerIndex is GA there) and 1.37; a mutated
   manifest must fail, so the validator is known to validate.
2. The Indexed Job is played locally as Kubernetes would run it: one process per completion index, all at once,
   each running the container's command with the container's environment plus JOB_COMPLETION_INDEX, the
   ConfigMap's spec.yaml at /spec and the volume at /data (both mapped to temporary directories). The dataset
   must be byte-identical to a local `pedsynth generate` of the original spec.

Usage: python3 tests/k8s_manifest.py --pedsynth PATH
"""

import argparse
import copy
import hashlib
import os
import pathlib
import subprocess
import sys
import tempfile

import kubernetes_validate
import yaml

REPO = pathlib.Path(__file__).resolve().parent.parent
# An override, to check that it reaches the pods (through the resolved spec in the ConfigMap).
SETS = ["dataset.seed=8"]
VERSIONS = ["1.33.0", "1.37.0"]


def set_args():
    return [a for s in SETS for a in ("--set", s)]


def files(root):
    root = pathlib.Path(root)
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and not p.name.startswith(".pedsynth.")
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pedsynth", required=True)
    args = ap.parse_args()
    pedsynth = str(pathlib.Path(args.pedsynth).resolve())
    spec = REPO / "tests" / "data" / "specs" / "cluster_small.yaml"
    completions = 3
    text = subprocess.run(
        [pedsynth, "k8s", str(spec), "--out", "datasets/small", "--completions", str(completions),
         "--pvc", "pedsynth-data", "--cpus", "1", "--memory", "2Gi", *set_args()],
        check=True, capture_output=True, text=True,
    ).stdout
    docs = [d for d in yaml.safe_load_all(text) if d]
    kinds = [d["kind"] for d in docs]
    assert kinds == ["ConfigMap", "Job"], kinds

    # 1. The Kubernetes schemas, strict.
    for version in VERSIONS:
        for doc in docs:
            kubernetes_validate.validate(doc, version, strict=True)
    bad = copy.deepcopy(docs[1])
    bad["spec"]["template"]["spec"]["containers"][0]["volumeMount"] = []
    bad2 = copy.deepcopy(docs[1])
    bad2["spec"]["completions"] = "three"
    for mutant in (bad, bad2):
        try:
            kubernetes_validate.validate(mutant, VERSIONS[0], strict=True)
        except kubernetes_validate.ValidationError:
            pass
        else:
            sys.exit("k8s: a mutated Job validated; the validator is not validating")
    job = docs[1]["spec"]
    assert job["completionMode"] == "Indexed" and job["completions"] == completions, job
    pod = job["template"]["spec"]
    container = pod["containers"][0]
    mounts = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}
    volumes = {v["name"]: v for v in pod["volumes"]}
    assert volumes["spec"]["configMap"]["name"] == docs[0]["metadata"]["name"]
    assert volumes["data"]["persistentVolumeClaim"]["claimName"] == "pedsynth-data"

    # 2. The Job played locally.
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        spec_dir, data_dir = tmp / "spec", tmp / "data"
        spec_dir.mkdir()
        data_dir.mkdir()
        for name, content in docs[0]["data"].items():
            (spec_dir / name).write_text(content)
        remap = {mounts["spec"]: str(spec_dir), mounts["data"]: str(data_dir)}

        def host_path(arg):
            for mount, local in remap.items():
                if arg == mount or arg.startswith(mount + "/"):
                    return local + arg[len(mount):]
            return arg

        command = [host_path(a) for a in container["command"]]
        assert command[0] == "pedsynth", command
        command[0] = pedsynth
        env = dict(os.environ)
        env.update({e["name"]: e["value"] for e in container["env"]})
        pods = []
        for index in range(completions):
            pod_env = dict(env, JOB_COMPLETION_INDEX=str(index))
            pods.append(subprocess.Popen(command, env=pod_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                         text=True))
        for index, p in enumerate(pods):
            out, err = p.communicate()
            if p.returncode != 0:
                sys.exit(f"k8s: pod {index} failed ({p.returncode}):\n{err}")
            expected = f"shard {index}/{completions} (from the Kubernetes Indexed Job's environment)"
            if expected not in err:
                sys.exit(f"k8s: pod {index} did not take its shard from JOB_COMPLETION_INDEX:\n{err}")
        single = tmp / "single"
        subprocess.run([pedsynth, "generate", str(spec), "--out", str(single), "--quiet", *set_args()],
                       check=True, stdout=subprocess.DEVNULL)
        a, b = files(single), files(data_dir / "datasets" / "small")
        if a != b:
            differ = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
            sys.exit(f"k8s: {len(differ)} files differ from a local run: {differ[:10]}")
    print(f"k8s: ConfigMap + Indexed Job valid (strict) for Kubernetes {', '.join(VERSIONS)}; "
          f"{completions} pods played locally wrote {len(a)} files byte-identical to a local run")


if __name__ == "__main__":
    main()
