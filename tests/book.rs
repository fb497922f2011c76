//! The guide book (`docs/`, built by mdBook) and the README (issue 64): every link resolves and
//! stays where mdBook can serve it, every chapter is in `SUMMARY.md`, the getting-started chapter's
//! commands and graph run from an empty folder and make the files it shows, the troubleshooting
//! chapter's messages are what pyrograph prints, and every other command names a real subcommand,
//! real flags and real files. `REGENERATE=1` renews the getting-started picture.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};
use std::process::{Command, Output};

use pulldown_cmark::{CodeBlockKind, Event, HeadingLevel, Parser, Tag, TagEnd};
use pyrograph_testing::workspace;

/// What a Markdown file holds that these tests read.
#[derive(Default)]
struct Doc {
    /// Link and image targets, as written.
    links: Vec<String>,
    /// Heading ids as mdBook (and GitHub) make them, duplicates numbered.
    anchors: BTreeSet<String>,
    /// Fenced code blocks in order: (language, text), with the `## ` heading they sit under.
    blocks: Vec<Block>,
}

struct Block {
    lang: String,
    text: String,
    section: String,
}

/// mdBook's `normalize_id`: letters, digits, `_` and `-` kept (lower-cased), spaces to `-`, the
/// rest dropped. GitHub's rule gives the same ids for the headings these files use.
fn slug(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| match c {
            c if c.is_alphanumeric() || c == '_' || c == '-' => Some(c.to_ascii_lowercase()),
            c if c.is_whitespace() => Some('-'),
            _ => None,
        })
        .collect()
}

fn read_doc(path: &Path) -> Doc {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut doc = Doc::default();
    let mut heading: Option<(HeadingLevel, String)> = None;
    let mut block: Option<(String, String)> = None;
    let mut section = String::new();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for event in Parser::new(&text) {
        match event {
            Event::Start(Tag::Link { dest_url, .. }) | Event::Start(Tag::Image { dest_url, .. }) => {
                doc.links.push(dest_url.to_string())
            }
            Event::Start(Tag::Heading { level, .. }) => heading = Some((level, String::new())),
            Event::End(TagEnd::Heading(_)) => {
                let (level, title) = heading.take().expect("a heading ends after it starts");
                let id = slug(&title);
                let n = seen.entry(id.clone()).or_insert(0);
                doc.anchors.insert(if *n == 0 { id.clone() } else { format!("{id}-{n}") });
                *n += 1;
                if level == HeadingLevel::H2 {
                    section = title;
                }
            }
            Event::Start(Tag::CodeBlock(CodeBlockKind::Fenced(lang))) => block = Some((lang.to_string(), String::new())),
            Event::End(TagEnd::CodeBlock) => {
                if let Some((lang, text)) = block.take() {
                    doc.blocks.push(Block { lang, text, section: section.clone() });
                }
            }
            Event::Text(t) | Event::Code(t) => {
                if let Some((_, title)) = heading.as_mut() {
                    title.push_str(&t);
                } else if let Some((_, text)) = block.as_mut() {
                    text.push_str(&t);
                }
            }
            _ => {}
        }
    }
    doc
}

fn docs_dir() -> PathBuf {
    workspace().join("docs")
}

/// The chapters `SUMMARY.md` lists, as paths under `docs/`.
fn chapters() -> Vec<PathBuf> {
    let summary = read_doc(&docs_dir().join("SUMMARY.md"));
    assert!(summary.links.len() >= 20, "SUMMARY.md lists {} chapters", summary.links.len());
    summary.links.iter().map(|l| docs_dir().join(l)).collect()
}

/// `a/b/../c` without touching the disk (a link may name a file that is missing: that is the
/// error to report, not a canonicalize failure).
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// Every problem with the links of `file`; `book` is the book's folder when the file is a chapter,
/// whose links must stay inside it and reach chapters (mdBook renders only what SUMMARY.md lists).
fn link_problems(
    file: &Path,
    book: Option<&Path>,
    chapters: &BTreeSet<PathBuf>,
    docs: &mut BTreeMap<PathBuf, Doc>,
) -> Vec<String> {
    let links = docs.entry(file.to_path_buf()).or_insert_with(|| read_doc(file)).links.clone();
    let mut problems = Vec::new();
    let name = file.strip_prefix(workspace()).unwrap_or(file).display().to_string();
    for link in links {
        if ["http://", "https://", "mailto:"].iter().any(|s| link.starts_with(s)) {
            continue;
        }
        let (path, anchor) = link.split_once('#').map_or((link.as_str(), None), |(p, a)| (p, Some(a)));
        let target =
            if path.is_empty() { file.to_path_buf() } else { normalize(&file.parent().expect("a file has a folder").join(path)) };
        if !target.exists() {
            problems.push(format!("{name}: link {link}: {} does not exist", target.display()));
            continue;
        }
        let is_md = target.extension().is_some_and(|e| e == "md");
        if book.is_some_and(|b| !target.starts_with(b)) {
            problems.push(format!("{name}: link {link} leaves docs/ (mdBook does not serve it): name the file instead"));
        } else if book.is_some() && is_md && !chapters.contains(&target) {
            problems.push(format!("{name}: link {link}: {} is not in SUMMARY.md", target.display()));
        }
        if let (Some(anchor), true) = (anchor, is_md) {
            let doc = docs.entry(target.clone()).or_insert_with(|| read_doc(&target));
            if !doc.anchors.contains(anchor) {
                problems.push(format!("{name}: link {link}: no heading with the id '{anchor}'"));
            }
        }
    }
    problems
}

#[test]
fn every_link_in_the_readme_and_the_book_resolves() {
    let chapters: BTreeSet<PathBuf> = chapters().into_iter().collect();
    let mut docs = BTreeMap::new();
    let book = Some(docs_dir());
    let mut problems = link_problems(&workspace().join("README.md"), None, &chapters, &mut docs);
    problems.extend(link_problems(&docs_dir().join("SUMMARY.md"), book.as_deref(), &chapters, &mut docs));
    for chapter in &chapters {
        problems.extend(link_problems(chapter, book.as_deref(), &chapters, &mut docs));
    }
    assert!(problems.is_empty(), "{} broken link(s):\n{}", problems.len(), problems.join("\n"));
    let readme = std::fs::read_to_string(workspace().join("README.md")).expect("README.md");
    assert!(readme.lines().count() < 250, "README.md has {} lines: the guide book is where detail goes", readme.lines().count());
}

#[test]
fn the_link_check_catches_a_missing_file_an_anchor_and_a_link_out_of_the_book() {
    let dir = tempfile::tempdir().expect("temp dir");
    let book = dir.path().join("book");
    std::fs::create_dir(&book).expect("mkdir");
    let page = book.join("page.md");
    std::fs::write(book.join("other.md"), "# Other\n\n## A part\n").expect("write");
    std::fs::write(book.join("orphan.md"), "# Orphan\n").expect("write");
    std::fs::write(dir.path().join("x.md"), "# X\n").expect("write");
    let links =
        "[ok](other.md#a-part) [gone](missing.md) [bad](other.md#no-part) [self](#page) [out](../x.md) [orphan](orphan.md)";
    std::fs::write(&page, format!("# Page\n\n{links}\n")).expect("write");
    let chapters = [book.join("other.md"), page.clone()].into_iter().collect();
    let problems = link_problems(&page, Some(&book), &chapters, &mut BTreeMap::new());
    assert_eq!(problems.len(), 4, "{problems:#?}");
    assert!(problems[0].contains("missing.md") && problems[0].contains("does not exist"));
    assert!(problems[1].contains("no heading with the id 'no-part'"));
    assert!(problems[2].contains("../x.md leaves docs/"), "{}", problems[2]);
    assert!(problems[3].contains("orphan.md") && problems[3].contains("not in SUMMARY.md"), "{}", problems[3]);
    // The README is not a chapter: it may link anywhere in the checkout.
    assert_eq!(link_problems(&page, None, &chapters, &mut BTreeMap::new()).len(), 2);
}

#[test]
fn every_markdown_file_under_docs_is_a_chapter() {
    let chapters: BTreeSet<PathBuf> = chapters().into_iter().collect();
    let mut orphans = Vec::new();
    let mut stack = vec![docs_dir()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("docs/ reads") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "md")
                && path.file_name().is_some_and(|n| n != "SUMMARY.md")
                && !chapters.contains(&path)
            {
                orphans.push(path.display().to_string());
            }
        }
    }
    assert!(orphans.is_empty(), "not in SUMMARY.md (mdBook would not render them): {orphans:?}");
}

/// A folder whose `pyrograph` is the binary under test, first on the `PATH`, so the chapters'
/// command lines run as written through `sh`.
struct Shell {
    _bin: tempfile::TempDir,
    path: String,
}

impl Shell {
    fn new() -> Self {
        let bin = tempfile::tempdir().expect("temp dir");
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_pyrograph"), bin.path().join("pyrograph")).expect("symlink");
        let path = format!("{}:{}", bin.path().display(), std::env::var("PATH").unwrap_or_default());
        Shell { _bin: bin, path }
    }

    fn run(&self, line: &str, cwd: &Path) -> Output {
        Command::new("sh")
            .args(["-c", line])
            .current_dir(cwd)
            .env("PATH", &self.path)
            .env_remove("PYROGRAPH_FOOTAGE")
            .env_remove("PYROGRAPH_PRESET_PATH")
            .output()
            .expect("sh runs")
    }
}

/// Lines of a shell block, with `\` continuations joined and comments and blanks dropped.
fn command_lines(block: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut current = String::new();
    for line in block.lines() {
        let line = line.trim();
        if let Some(head) = line.strip_suffix('\\') {
            current.push_str(head);
            current.push(' ');
            continue;
        }
        current.push_str(line);
        let whole = std::mem::take(&mut current);
        if !whole.is_empty() && !whole.starts_with('#') {
            lines.push(whole);
        }
    }
    lines
}

fn is_shell(lang: &str) -> bool {
    matches!(lang, "sh" | "bash" | "console" | "shell")
}

/// Steps of the getting-started chapter that the test does not run, and why: installing the
/// checkout takes minutes and the binary under test stands in for it; the editor needs a display
/// (the editor's own tests open it under Xvfb).
const NOT_RUN: &[&str] = &["cargo install --locked --path .", "cargo run --release -p pyrograph-editor -- my-fire/fire.ron"];

#[test]
fn getting_started_runs_from_an_empty_folder_and_makes_the_files_it_shows() {
    let doc = read_doc(&docs_dir().join("getting-started.md"));
    let shell = Shell::new();
    let root = tempfile::tempdir().expect("temp dir");
    let mut cwd = root.path().to_path_buf();
    let (mut ran, mut graphs, mut listings) = (0, 0, 0);
    let mut last: Option<(String, Output)> = None;
    for block in &doc.blocks {
        if block.lang == "ron" {
            let name = block
                .text
                .lines()
                .next()
                .and_then(|l| l.strip_prefix("// file: "))
                .expect("a graph in the chapter starts with `// file: NAME`");
            std::fs::write(cwd.join(name.trim()), &block.text).expect("write the graph");
            graphs += 1;
        } else if block.lang == "text" {
            let (line, out) = last.take().expect("a text block shows the output of the command block before it");
            assert_eq!(
                String::from_utf8_lossy(&out.stdout),
                block.text,
                "`{line}` printed something else than the chapter shows"
            );
            listings += 1;
        } else if is_shell(&block.lang) {
            for line in command_lines(&block.text) {
                if NOT_RUN.contains(&line.as_str()) {
                    continue;
                }
                if let Some(dir) = line.strip_prefix("cd ") {
                    cwd = cwd.join(dir.trim());
                    continue;
                }
                let out = shell.run(&line, &cwd);
                assert!(out.status.success(), "`{line}` failed:\n{}", String::from_utf8_lossy(&out.stderr));
                last = Some((line, out));
                ran += 1;
            }
        }
    }
    assert!(ran >= 9 && graphs == 1 && listings >= 4, "ran {ran} commands, wrote {graphs} graphs, compared {listings} listings");
    check_picture(&cwd.join("wedge/wedges.png"), &docs_dir().join("images/getting-started-wedge.png"));
}

/// The chapter's picture is the wedge sheet its commands make: renewed with `REGENERATE=1`, else
/// it must be there at the size the commands make it.
fn check_picture(made: &Path, shown: &Path) {
    if std::env::var("REGENERATE").is_ok_and(|v| v == "1") {
        std::fs::copy(made, shown).expect("renew the picture");
    }
    let made = image::image_dimensions(made).expect("the wedge sheet");
    let shown = image::image_dimensions(shown).unwrap_or_else(|e| panic!("{}: {e} (REGENERATE=1 makes it)", shown.display()));
    assert_eq!(made, shown, "the chapter's picture is stale: REGENERATE=1 renews it");
}

#[test]
fn troubleshooting_shows_the_messages_pyrograph_prints() {
    let doc = read_doc(&docs_dir().join("troubleshooting.md"));
    let shell = Shell::new();
    let scratch = tempfile::tempdir().expect("temp dir");
    let scratch_dir = scratch.path().display().to_string();
    // The chapter's commands write under /tmp/; the test's own folder stands in for it.
    let local = |s: &str| s.replace("/tmp/", &format!("{scratch_dir}/"));
    let mut checked = 0;
    let mut last: Option<Output> = None;
    for block in &doc.blocks {
        if is_shell(&block.lang) {
            for line in command_lines(&block.text) {
                last = Some(shell.run(&local(&line), &workspace()));
            }
        } else if block.lang == "text" {
            let out = last.take().unwrap_or_else(|| panic!("'{}': a message follows the command that prints it", block.section));
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "'{}' should fail with status 1:\n{stderr}", block.section);
            for want in block.text.lines() {
                assert!(
                    stderr.lines().any(|l| l == local(want)),
                    "'{}': pyrograph no longer prints\n  {want}\nit printed:\n{stderr}",
                    block.section
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 10, "the chapter shows {checked} errors; it promises the ten met most");
}

/// `pyrograph [SUB [SUBSUB]] --help`, and the subcommands its `Commands:` section lists.
fn help(shell: &Shell, words: &[&str]) -> (String, Vec<String>) {
    let out = shell.run(&format!("pyrograph {} --help", words.join(" ")), &workspace());
    assert!(out.status.success(), "pyrograph {words:?} --help failed");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let commands = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect();
    (text, commands)
}

/// The words of a command line after the program, when the line runs pyrograph (as `pyrograph`,
/// `$B` or `target/release/pyrograph`, after any `NAME=value` assignments).
fn pyrograph_args(line: &str) -> Option<Vec<String>> {
    let words = shlex::split(line).unwrap_or_else(|| panic!("`{line}` is not a shell line"));
    let mut words = words.into_iter().skip_while(|w| w.contains('=') && !w.starts_with('-'));
    let program = words.next()?;
    ["pyrograph", "$B", "target/release/pyrograph"].contains(&program.as_str()).then(|| words.collect())
}

fn command_problems(line: &str, shell: &Shell, top: &[String], check_files: bool) -> Vec<String> {
    let Some(args) = pyrograph_args(line) else { return Vec::new() };
    let Some(sub) = args.first() else { return Vec::new() };
    if !top.contains(sub) {
        return vec![format!("`{line}`: pyrograph has no subcommand '{sub}'")];
    }
    let (mut text, subs) = help(shell, &[sub]);
    if let Some(next) = args.get(1).filter(|n| subs.contains(n)) {
        text = help(shell, &[sub, next]).0;
    }
    let mut problems = Vec::new();
    for arg in &args[1..] {
        let flag = arg.split('=').next().unwrap_or(arg);
        if flag.starts_with("--") && !text.contains(&format!("{flag} ")) && !text.contains(&format!("{flag}\n")) {
            problems.push(format!("`{line}`: `pyrograph {sub}` has no flag {flag}"));
        }
        // `--input clip=graphs/x.ron` names a file after its input's name.
        let file = if arg.starts_with('-') { arg.as_str() } else { arg.rsplit_once('=').map_or(arg.as_str(), |(_, f)| f) };
        let local_file = !file.starts_with('/') && !file.contains('$') && !file.starts_with('-');
        if check_files
            && local_file
            && (file.ends_with(".ron") || file.starts_with("graphs/"))
            && !workspace().join(file).exists()
        {
            problems.push(format!("`{line}`: {arg} does not exist in the checkout"));
        }
    }
    problems
}

#[test]
fn every_command_in_the_readme_and_the_book_names_real_subcommands_flags_and_files() {
    let shell = Shell::new();
    let (_, top) = help(&shell, &[]);
    assert!(top.contains(&"render".to_string()), "pyrograph --help lists its commands: {top:?}");
    let mut files = vec![workspace().join("README.md")];
    files.extend(chapters());
    let (mut problems, mut seen) = (Vec::new(), 0);
    for file in &files {
        // The getting-started commands run for real in a folder they make, so their files are theirs.
        let check_files = !file.ends_with("getting-started.md");
        for block in read_doc(file).blocks.iter().filter(|b| is_shell(&b.lang)) {
            for line in command_lines(&block.text) {
                seen += usize::from(pyrograph_args(&line).is_some());
                problems.extend(command_problems(&line, &shell, &top, check_files));
            }
        }
    }
    assert!(seen >= 40, "found only {seen} pyrograph command lines");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    let broken = command_problems("pyrograph render graphs/nope.ron --frobnicate 3", &shell, &top, true);
    assert_eq!(broken.len(), 2, "the check itself catches a flag and a file: {broken:?}");
}

#[test]
fn every_whole_graph_in_the_readme_and_the_book_loads() {
    let scratch = tempfile::tempdir().expect("temp dir");
    let mut files = vec![workspace().join("README.md")];
    files.extend(chapters());
    let mut loaded = 0;
    for file in &files {
        for block in read_doc(file).blocks.iter().filter(|b| b.lang == "ron") {
            let body: String = block.text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
            // Fragments (a node or two to paste into a graph) are not documents on their own.
            if !body.trim_start().starts_with('(') || !body.contains("nodes:") {
                continue;
            }
            let path = scratch.path().join(format!("graph{loaded}.ron"));
            std::fs::write(&path, &block.text).expect("write");
            let out = Command::new(env!("CARGO_BIN_EXE_pyrograph"))
                .args(["info", &path.display().to_string()])
                .env("PYROGRAPH_FOOTAGE", scratch.path())
                .output()
                .expect("pyrograph runs");
            assert!(
                out.status.success(),
                "{} ('{}'): the graph does not load:\n{}",
                file.display(),
                block.section,
                String::from_utf8_lossy(&out.stderr)
            );
            loaded += 1;
        }
    }
    assert!(loaded >= 3, "only {loaded} whole graphs found");
}
