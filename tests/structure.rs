//! The module graph has no circles, at two grains: the top-level modules of `src/`
//! (each concept uses only those below it), and every module file (`renderer::indirect`,
//! `cli::chart`, ...), where a path names the deepest module it reaches (`crate::x::y`,
//! `super::y`, or a child module's name). A child module may extend its parent's own
//! types (`impl Renderer` in `renderer/sync.rs`), so naming an ancestor is not an edge;
//! the files a frame runs through must not name theirs at all.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

type Graph = BTreeMap<String, BTreeSet<String>>;

/// Every module file of `src/` (but `lib` and `main`) as its module path, with its code:
/// comments and `#[cfg(test)]` modules cut.
fn module_files() -> Vec<(Vec<String>, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let rel = path.strip_prefix(&src).unwrap().with_extension("");
            let mut module: Vec<String> = rel
                .iter()
                .map(|s| s.to_str().unwrap().to_string())
                .collect();
            if module.last().is_some_and(|m| m == "mod") {
                module.pop();
            }
            if module == ["lib"] || module == ["main"] {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let text = text.split("#[cfg(test)]").next().unwrap_or("");
            let code: Vec<&str> = text
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect();
            files.push((module, code.join("\n")));
        }
    }
    files
}

/// The paths `code` names: each `crate::a::b` (every item of `crate::{a, b::c}` too) and
/// each `super::a`, as segments from the crate root, seen from `module` (its file's
/// path); and each `child::` of a child module of `module`.
fn named_paths(module: &[String], code: &str, modules: &BTreeSet<Vec<String>>) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let parent = &module[..module.len().saturating_sub(1)];
    let starts: [(&str, &[String]); 2] = [("crate::", &[]), ("super::", parent)];
    for (prefix, base) in starts {
        for (i, _) in code.match_indices(prefix) {
            // `pub(in crate::renderer)` limits an item's reach; it names no dependency.
            if code[..i].ends_with("::")
                || code[..i].ends_with("(in ")
                || code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_')
            {
                continue;
            }
            for path in group_items(&code[i + prefix.len()..]) {
                out.push([base.to_vec(), path].concat());
            }
        }
    }
    for child in modules
        .iter()
        .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
    {
        let name = format!("{}::", child.last().unwrap());
        for (i, _) in code.match_indices(&name) {
            let before = code[..i].chars().last();
            if !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                out.push(child.clone());
            }
        }
    }
    out
}

/// The paths at the start of `rest`: `a::b::C` -> [a, b, C]; `{a::B, c}` -> both.
fn group_items(rest: &str) -> Vec<Vec<String>> {
    let items: Vec<&str> = match rest.strip_prefix('{') {
        Some(g) => g[..g.find('}').unwrap_or(g.len())].split(',').collect(),
        None => vec![rest],
    };
    items
        .into_iter()
        .map(|item| {
            let path: String = item
                .trim()
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            path.split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect()
        })
        .filter(|p: &Vec<String>| !p.is_empty())
        .collect()
}

/// The deepest module `path` reaches.
fn resolve(path: &[String], modules: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| modules.contains(p))
}

/// Module file -> the modules it names (not itself, not its ancestors).
fn file_graph() -> Graph {
    let files = module_files();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut graph = Graph::new();
    for (module, code) in &files {
        let uses = graph.entry(module.join("::")).or_default();
        for path in named_paths(module, code, &modules) {
            if let Some(target) = resolve(&path, &modules)
                && !module.starts_with(&target)
            {
                uses.insert(target.join("::"));
            }
        }
    }
    graph
}

/// Top-level module -> the top-level modules its files name.
fn top_level_graph() -> Graph {
    let mut graph = Graph::new();
    for (module, uses) in file_graph() {
        let top = |m: &str| m.split("::").next().unwrap().to_string();
        let entry = graph.entry(top(&module)).or_default();
        entry.extend(uses.iter().map(|u| top(u)).filter(|u| *u != top(&module)));
    }
    graph
}

/// Panics naming a circle of `graph`, if it has one (depth-first search for a back edge).
fn assert_no_circle(graph: &Graph) {
    fn visit(m: &str, graph: &Graph, path: &mut Vec<String>, done: &mut BTreeSet<String>) {
        if let Some(at) = path.iter().position(|p| p == m) {
            panic!("import circle: {} -> {m}", path[at..].join(" -> "));
        }
        if !done.insert(m.to_string()) {
            return;
        }
        path.push(m.to_string());
        for next in graph.get(m).into_iter().flatten() {
            visit(next, graph, path, done);
        }
        path.pop();
    }
    let mut done = BTreeSet::new();
    for m in graph.keys() {
        visit(m, graph, &mut Vec::new(), &mut done);
    }
}

#[test]
fn top_level_modules_form_no_circle() {
    let graph = top_level_graph();
    assert!(graph.len() > 10, "{graph:?}");
    assert!(graph["renderer"].contains("cull"), "{graph:?}");
    assert_no_circle(&graph);
}

#[test]
fn module_files_form_no_circle() {
    let graph = file_graph();
    assert!(
        graph["renderer::display::indirect"].contains("renderer::culler"),
        "{graph:?}"
    );
    assert!(graph["renderer"].contains("renderer::display"), "{graph:?}");
    assert_no_circle(&graph);
}

/// The files of `renderer/` that serve the embedding API beside `renderer/mod.rs`: a
/// frame's calls (`submit`), the diagnostics and the option checks. They assemble the
/// levels, so they may name them all.
const RENDERER_API: [&str; 3] = ["submit", "diagnostics", "checks"];

/// The modules of `renderer/` below `renderer` itself, but the API's files.
fn renderer_inner(files: &[(Vec<String>, String)]) -> Vec<&(Vec<String>, String)> {
    (files.iter())
        .filter(|(m, _)| m.len() >= 2 && m[0] == "renderer")
        .filter(|(m, _)| !(m.len() == 2 && RENDERER_API.contains(&m[1].as_str())))
        .collect()
}

/// From `Renderer::prepare` to the last draw a reader never climbs back into
/// `renderer/mod.rs`: the frame's files name siblings and lower modules only.
#[test]
fn the_files_a_frame_runs_through_never_name_their_parent() {
    let files = module_files();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let inner = renderer_inner(&files);
    assert!(inner.len() > 12, "{}", inner.len());
    for (module, code) in inner {
        for path in named_paths(module, code, &modules) {
            let target = resolve(&path, &modules);
            assert_ne!(
                target.as_deref(),
                Some(&module[..1]),
                "{} names {}",
                module.join("::"),
                path.join("::")
            );
        }
    }
}

/// The renderer's rooms by the chapter's levels (`renderer/frame/`, `renderer/display/`,
/// `renderer/eye/`), one way: the frame level's files never name the display level's
/// room, nor the other way, and the eye level names neither; a display holds its eyes,
/// so the display's room alone names the eye's. They meet otherwise only through what
/// all name below them (the plan, the view, the culler, the pass recorder). Those shared
/// modules name no room; only the embedding API's files assemble them.
#[test]
fn the_levels_rooms_name_each_other_only_through_the_plan_and_the_view() {
    let files = module_files();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let room = |m: &[String]| match m {
        [r, level, ..]
            if r == "renderer" && ["frame", "display", "eye"].contains(&level.as_str()) =>
        {
            Some(level.clone())
        }
        _ => None,
    };
    let mut seen = BTreeSet::new();
    for (module, code) in renderer_inner(&files) {
        let own = room(module);
        seen.extend(own.clone());
        for path in named_paths(module, code, &modules) {
            let Some(target) = resolve(&path, &modules) else {
                continue;
            };
            let theirs = room(&target);
            let holds = own.as_deref() == Some("display") && theirs.as_deref() == Some("eye");
            assert!(
                theirs.is_none() || theirs == own || holds,
                "{} names {} in another level's room",
                module.join("::"),
                target.join("::")
            );
        }
    }
    assert_eq!(seen.len(), 3, "{seen:?}");
}

#[test]
fn the_module_reader_sees_grouped_nested_relative_and_child_paths() {
    let modules: BTreeSet<Vec<String>> = [
        vec!["rig"],
        vec!["scene"],
        vec!["frustum"],
        vec!["renderer"],
        vec!["renderer", "culler"],
        vec!["renderer", "frame"],
    ]
    .into_iter()
    .map(|m| m.into_iter().map(String::from).collect())
    .collect();
    let module = |m: &[&str]| m.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let code = "use crate::{rig::Rig, scene};\nlet x = crate::frustum::ROUNDING_SLACK;\nuse super::frame::FramePlan;";
    let named: Vec<_> = named_paths(&module(&["renderer", "culler"]), code, &modules)
        .iter()
        .filter_map(|p| resolve(p, &modules))
        .map(|m| m.join("::"))
        .collect();
    assert_eq!(named, ["rig", "scene", "frustum", "renderer::frame"]);
    let parent = named_paths(
        &module(&["renderer"]),
        "let c = culler::Culler::new();",
        &modules,
    );
    assert_eq!(parent, [module(&["renderer", "culler"])]);
}

/// The fields of `struct name` in `file` (under `src/`), each as its line of code.
fn struct_fields(file: &str, name: &str) -> Vec<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(file);
    let text = std::fs::read_to_string(path).unwrap();
    let start = text
        .find(&format!("pub struct {name} {{"))
        .unwrap_or_else(|| panic!("no struct {name} in {file}"));
    let body = &text[start..];
    let body = &body[body.find('{').unwrap() + 1..body.find("\n}").unwrap()];
    (body.lines())
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("//") && !l.starts_with('#'))
        .map(String::from)
        .collect()
}

/// The chapter's levels are values: what exists once per display is one field of one
/// `DisplayPlan` or `Display`, never a vector indexed by display beside `displays`.
/// Every other vector of the frame's plan and of the renderer is listed here with what
/// it is indexed by, so a new one must say why it is not per display.
#[test]
fn a_frame_plan_and_a_renderer_keep_their_displays_in_one_vector() {
    let per_what = [
        (
            "renderer/plan.rs",
            "FramePlan",
            "displays: Vec<DisplayPlan>,",
        ),
        ("renderer/plan.rs", "FramePlan", "marks: Vec<u32>,"),
        ("renderer/mod.rs", "Renderer", "displays: Vec<Display>,"),
        ("renderer/mod.rs", "Renderer", "passes: Vec<PassRecord>,"),
    ];
    for (file, name) in [
        ("renderer/plan.rs", "FramePlan"),
        ("renderer/mod.rs", "Renderer"),
    ] {
        let fields = struct_fields(file, name);
        assert!(fields.len() > 4, "{name}: {fields:?}");
        for field in fields.iter().filter(|f| f.contains("Vec<")) {
            let field = field.trim_start_matches("pub ");
            let listed = (per_what.iter()).any(|&(f, n, l)| (f, n, l) == (file, name, field));
            assert!(listed, "{name} has a vector that is not listed: {field}");
        }
        assert!(
            !fields.iter().any(|f| f.contains("Vec<Option<")),
            "{name}: {fields:?}"
        );
    }
}

/// `impl Renderer` keeps the embedding API and hands each level to its type: it lives
/// in at most two files (making the renderer and asking it things; a frame's calls).
#[test]
fn the_renderer_is_implemented_in_at_most_two_files() {
    let files = module_files();
    let implementing: Vec<String> = (files.iter())
        .filter(|(_, code)| code.contains("impl Renderer {"))
        .map(|(m, _)| m.join("::"))
        .collect();
    assert!(!implementing.is_empty());
    assert!(implementing.len() <= 2, "{implementing:?}");
}

#[test]
fn the_field_reader_sees_each_field_of_the_frame_plan() {
    let fields = struct_fields("renderer/plan.rs", "FramePlan");
    assert!(
        fields
            .iter()
            .any(|f| f == "pub displays: Vec<DisplayPlan>,"),
        "{fields:?}"
    );
    assert!(
        fields.iter().any(|f| f == "pub frame: FrameContext,"),
        "{fields:?}"
    );
}
