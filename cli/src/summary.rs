//! `coray summary FILE`: the README's results table, read from a speed
//! table that `coray bench --table speed` wrote (docs/speed-1024.txt), so
//! that no figure in the README is copied by hand.

/// One row of a speed table: scene, ray set, threads, best method, the
/// best over Embree's one-ray and packet calls, mismatches, and every
/// method's Mrays/s by column name.
struct Row<'a> {
    scene: &'a str,
    set: &'a str,
    threads: u32,
    best: &'a str,
    x_e1: f64,
    x_e8: f64,
    mismatches: u64,
    methods: Vec<(&'a str, Option<f64>)>,
    embree1: f64,
}

/// The Markdown table of `text` (a speed table): per scene at one thread,
/// coray's best method on each ray set against the call the targets name
/// (primary and shadow against Embree's packets of 8, incoherent and
/// diffuse against its one-ray call), the wide tracer's one-ray calls on
/// incoherent rays against `rtcIntersect1`, and the mismatches of every
/// thread count; then how many ratios are below 1.
pub fn summary(text: &str) -> Result<String, String> {
    let mut lines = text.lines();
    let command = lines
        .next()
        .filter(|l| l.starts_with("$ coray bench --table speed"))
        .ok_or("not a speed table: its first line is not the `coray bench --table speed` that wrote it")?;
    let header: Vec<&str> = lines
        .next()
        .ok_or("no column header")?
        .split_whitespace()
        .collect();
    // The header names "best (Mr/s)" in two words, the row one value.
    let method_names: Vec<&str> = header
        .iter()
        .skip_while(|h| **h != "mism")
        .skip(1)
        .copied()
        .collect();
    let mut rows = Vec::new();
    for line in lines.take_while(|l| !l.starts_with("columns:")) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 11 {
            continue;
        }
        let num = |s: &str| {
            s.parse::<f64>()
                .map_err(|_| format!("bad number `{s}` in: {line}"))
        };
        rows.push(Row {
            scene: f[0],
            set: f[1],
            threads: f[2]
                .parse()
                .map_err(|_| format!("bad thread count in: {line}"))?,
            best: f[4],
            embree1: num(f[6])?,
            x_e1: num(f[8])?,
            x_e8: num(f[9])?,
            mismatches: f[10]
                .parse()
                .map_err(|_| format!("bad mismatch count in: {line}"))?,
            methods: method_names
                .iter()
                .zip(&f[11..])
                .map(|(m, v)| (*m, v.parse().ok()))
                .collect(),
        });
    }
    if rows.is_empty() {
        return Err("no rows".into());
    }
    let mut scenes: Vec<&str> = Vec::new();
    for r in &rows {
        if !scenes.contains(&r.scene) {
            scenes.push(r.scene);
        }
    }
    let mut out = format!(
        "From `docs/speed-1024.txt` (`{}`): coray's best method on each ray set over the \
         Embree call named, one thread, 1024 x 1024; `wide-c1` is one \
         `coray_wide_tracer_intersect1` call per ray.\n\n\
         | scene | primary / rtcIntersect8 | shadow / rtcOccluded8 | incoherent / rtcIntersect1 \
         | diffuse / rtcIntersect1 | wide-c1 incoherent / rtcIntersect1 | mismatches |\n\
         |---|---|---|---|---|---|---:|\n",
        command.trim_start_matches("$ ")
    );
    let (mut below, mut total) = (0, 0);
    for s in &scenes {
        let find = |set: &str| {
            rows.iter()
                .find(|r| r.scene == *s && r.set == set && r.threads == 1)
        };
        let mut cell = |set: &str, packets: bool| -> String {
            match find(set) {
                None => "-".into(),
                Some(r) => {
                    let x = if packets { r.x_e8 } else { r.x_e1 };
                    total += 1;
                    below += usize::from(x < 1.0);
                    format!("{x:.2} ({})", r.best)
                }
            }
        };
        let primary = cell("primary", true);
        let shadow = cell("shadow", true);
        let incoherent = cell("incoherent", false);
        let diffuse = cell("diffuse", false);
        let wide_c1 = find("incoherent")
            .and_then(|r| {
                let (_, v) = r.methods.iter().find(|(m, _)| *m == "wide-c1")?;
                Some(format!("{:.2}", (*v)? / r.embree1))
            })
            .unwrap_or_else(|| "-".into());
        let mism: u64 = rows
            .iter()
            .filter(|r| r.scene == *s)
            .map(|r| r.mismatches)
            .sum();
        out += &format!(
            "| {} | {primary} | {shadow} | {incoherent} | {diffuse} | {wide_c1} | {mism} |\n",
            s.trim_end_matches(".obj")
        );
    }
    out += &format!("\nRatios below 1.0: {below} of {total}.\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "$ coray bench --table speed --res 8\n\
        scene set thr rays best (Mr/s) embree1 embree8 x e1 x e8 mism kd wide-c1\n\
        spd:a primary 1 64 kd-packet 2.00 1.00 2.50 2.00 0.80 0 1.00 0.50\n\
        spd:a incoherent 1 64 wide 3.00 2.00 1.00 1.50 3.00 0 1.00 1.80\n\
        spd:a primary 2 64 kd-packet 4.00 2.00 5.00 2.00 0.80 3 1.00 0.50\n\
        columns: legend\n";

    #[test]
    fn one_row_per_scene_with_the_targets_ratios() {
        let s = summary(TABLE).unwrap();
        assert!(s.contains("`coray bench --table speed --res 8`"), "{s}");
        assert!(
            s.contains("| spd:a | 0.80 (kd-packet) | - | 1.50 (wide) | - | 0.90 | 3 |"),
            "{s}"
        );
        assert!(s.contains("Ratios below 1.0: 1 of 2."), "{s}");
        assert!(summary("scene set\n").is_err());
    }
}
