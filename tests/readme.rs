//! The README's first screen against the binary: the main job's summary, as the README
//! prints it, is what `uncoil run scenes/yoga-mat.toml` prints now, wall times aside.

use std::path::Path;

use assert_cmd::Command;

/// The README's printed block: the lines of the first ```text fence that starts with the
/// main job's first line.
fn readme_block() -> String {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let start = readme
        .find("```text\nuncoil: yoga-mat")
        .expect("README shows the main job's summary in a ```text block");
    let body = &readme[start + "```text\n".len()..];
    let end = body.find("\n```").expect("the block is closed");
    body[..end + 1].to_owned()
}

/// The summary with its wall times (the only figures a machine changes) replaced by `_`:
/// `... simulated in 0.050 s wall (0.046 s to the bang); ...`.
fn without_wall_times(summary: &str) -> String {
    summary
        .lines()
        .map(|line| {
            let Some(at) = line.find(" s wall (") else {
                return line.to_owned();
            };
            let (head, tail) = line.split_at(at);
            let head = head.trim_end_matches(|c: char| c.is_ascii_digit() || c == '.');
            let tail = &tail[" s wall (".len()..];
            let close = tail.find(" s to the bang)").expect("the bang's wall time");
            format!("{head}_ s wall (_{}", &tail[close..])
        })
        .map(|line| line + "\n")
        .collect()
}

#[test]
fn the_readme_prints_what_the_main_job_prints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // Run from an empty folder, as the README does from the repository's root: the files go
    // into runs/yoga-mat/ there, and the summary names them so.
    let cwd = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("uncoil")
        .unwrap()
        .current_dir(cwd.path())
        .args(["run"])
        .arg(root.join("scenes/yoga-mat.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let printed = without_wall_times(&String::from_utf8(out.stdout).unwrap());
    let shown = without_wall_times(&readme_block());
    if printed != shown {
        let diff: Vec<String> = printed
            .lines()
            .zip(shown.lines())
            .filter(|(p, s)| p != s)
            .map(|(p, s)| format!("  README: {s}\n  now:    {p}"))
            .collect();
        panic!(
            "README.md's printed block is stale ({} lines now, {} in the README); \
             paste the main job's output into it:\n{}",
            printed.lines().count(),
            shown.lines().count(),
            diff.join("\n")
        );
    }
}

#[test]
fn wall_times_are_all_it_masks() {
    let line = "  352 links (32 per turn), 2991 steps, 2.376 s simulated in 0.050 s wall \
                (0.046 s to the bang); completed\n";
    assert_eq!(
        without_wall_times(line),
        "  352 links (32 per turn), 2991 steps, 2.376 s simulated in _ s wall (_ s to the \
         bang); completed\n"
    );
    assert_eq!(without_wall_times("a 0.050 s step\n"), "a 0.050 s step\n");
}

#[test]
fn the_readme_s_answer_for_the_yoga_mat_is_what_its_ensemble_prints() {
    // The README's table gives each share as mean ± standard error ± systematic band; the
    // first two are `uncoil run yoga-mat --ensemble 8`'s.
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let row = readme
        .lines()
        .find(|l| l.starts_with("| yoga mat (b/R = 1/12) |"))
        .expect("the README's answer has the yoga mat's row");
    let cells: Vec<&str> = row.split(" | ").collect();
    let cwd = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("uncoil")
        .unwrap()
        .current_dir(cwd.path())
        .args(["run", "yoga-mat", "--ensemble", "8"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let printed = String::from_utf8(out.stdout).unwrap();
    let figure = |label: &str| -> String {
        let line = printed
            .lines()
            .find(|l| l.trim_start().starts_with(label))
            .unwrap_or_else(|| panic!("`{label}` in:\n{printed}"));
        line[line.find(label).unwrap() + label.len()..]
            .trim()
            .trim_end_matches(" %")
            .to_owned()
    };
    let shares = [
        "floor impacts share",
        "floor friction share",
        "layers' impacts share",
        "layers' friction share",
        "freezing share",
        "numerical share",
    ];
    for (k, label) in shares.iter().enumerate() {
        let printed = figure(label);
        assert!(
            cells[k + 1].starts_with(&format!("{printed} ±")),
            "README's {label} `{}`, the ensemble prints `{printed}`",
            cells[k + 1]
        );
    }
}
