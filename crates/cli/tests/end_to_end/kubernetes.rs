//! deploy/kubernetes/rvtol-sharded-run.yaml: the manifest is the Indexed Job the docs
//! describe (index-selected shards, per-index retries, a merge Job), and the commands its
//! pods run, run here with their environment (a directory for the volume, fewer samples),
//! give the report of one `rvtol run` byte for byte.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::{run_rvtol, rvtol_binary, scenario, workspace_dir};
use yaml_rust2::{Yaml, YamlLoader};

fn manifest() -> Vec<Yaml> {
    let path = workspace_dir().join("deploy/kubernetes/rvtol-sharded-run.yaml");
    YamlLoader::load_from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn job<'a>(docs: &'a [Yaml], name: &str) -> &'a Yaml {
    docs.iter()
        .find(|d| d["kind"].as_str() == Some("Job") && d["metadata"]["name"].as_str() == Some(name))
        .unwrap_or_else(|| panic!("no Job {name}"))
}

/// The container's `sh -c` script and its environment.
fn container(job: &Yaml) -> (String, Vec<(String, String)>) {
    let pod = &job["spec"]["template"]["spec"];
    assert_eq!(pod["restartPolicy"].as_str(), Some("Never"));
    let containers = pod["containers"].as_vec().unwrap();
    assert_eq!(containers.len(), 1);
    let c = &containers[0];
    let command: Vec<&str> = c["command"]
        .as_vec()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    assert_eq!(&command[..2], ["sh", "-c"], "{command:?}");
    let env = c["env"]
        .as_vec()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["name"].as_str().unwrap().to_string(),
                e["value"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    // The volume is mounted where DATA points.
    assert_eq!(c["volumeMounts"][0]["mountPath"].as_str(), Some("/data"));
    (command[2].to_string(), env)
}

/// Runs a pod's script with its environment, DATA on `data`, `rvtol` on the PATH and the
/// given overrides.
fn run_pod(script: &str, env: &[(String, String)], data: &Path, overrides: &[(&str, String)]) {
    let bin = rvtol_binary().parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut command = Command::new("sh");
    command.arg("-c").arg(script).env("PATH", path);
    for (name, value) in env {
        command.env(name, value);
    }
    command.env("DATA", data);
    for (name, value) in overrides {
        command.env(name, value);
    }
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn indexed_job_pods_compute_the_run() {
    let docs = manifest();
    let shards = job(&docs, "rvtol-shards");
    let spec = &shards["spec"];
    assert_eq!(spec["completionMode"].as_str(), Some("Indexed"));
    let n = spec["completions"].as_i64().unwrap();
    assert!(n >= 2);
    assert_eq!(spec["parallelism"].as_i64(), Some(n));
    assert!(spec["backoffLimitPerIndex"].as_i64().unwrap() >= 1);
    let (script, env) = container(shards);
    assert!(
        env.contains(&("RVTOL_SHARDS".into(), n.to_string())),
        "{env:?}"
    );
    assert!(
        script.contains("--shard \"$JOB_COMPLETION_INDEX/$RVTOL_SHARDS\""),
        "{script}"
    );
    let merge = job(&docs, "rvtol-merge");
    let (merge_script, merge_env) = container(merge);
    assert!(merge_env.contains(&("RVTOL_SHARDS".into(), n.to_string())));
    assert!(docs
        .iter()
        .any(|d| d["kind"].as_str() == Some("PersistentVolumeClaim")));

    let data = std::env::temp_dir().join(format!("rvtol-k8s-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&data);
    std::fs::create_dir_all(&data).unwrap();
    let file = scenario("rv80e-contact.json");
    std::fs::copy(&file, data.join("scenario.json")).unwrap();
    // With the reducer file it names, beside it as in the repository (the recipe's note).
    std::fs::create_dir_all(data.join("reducers")).unwrap();
    std::fs::copy(
        workspace_dir().join("scenarios/reducers/rv80e.json"),
        data.join("reducers/rv80e.json"),
    )
    .unwrap();
    // The pods' own options, with fewer samples.
    let args = ("RVTOL_ARGS", "--samples 30000".to_string());
    // The indices in reverse, as pods finish in any order.
    for k in (0..n).rev() {
        run_pod(
            &script,
            &env,
            &data,
            &[args.clone(), ("JOB_COMPLETION_INDEX", k.to_string())],
        );
    }
    run_pod(
        &merge_script,
        &merge_env,
        &data,
        &[("RVTOL_WAIT_SECONDS", "0".into())],
    );
    let single = data.join("single.json");
    let out = run_rvtol(&[
        "run",
        &data.join("scenario.json").display().to_string(),
        "--samples",
        "30000",
        "--json",
        &single.display().to_string(),
        "-q",
    ]);
    assert!(out.status.success());
    let merged = std::fs::read(data.join("run/report.json")).unwrap();
    assert_eq!(merged, std::fs::read(&single).unwrap());
    // A lost shard: the merge pod waits, then names it and fails.
    std::fs::remove_file(data.join("run/shard-1.part")).unwrap();
    let bin = rvtol_binary().parent().unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg(&merge_script)
        .envs(merge_env.iter().map(|(a, b)| (a.clone(), b.clone())))
        .env("DATA", &data)
        .env("RVTOL_WAIT_SECONDS", "0")
        .env(
            "PATH",
            format!(
                "{}:{}",
                bin.display(),
                std::env::var("PATH").unwrap_or_default()
            ),
        )
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("shards missing after 0 s: 1"), "{stderr}");
    std::fs::remove_dir_all(&data).unwrap();
}
