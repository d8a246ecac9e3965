use bvseg_core::*;
use glam::DVec3;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let k: Option<usize> = std::env::args().nth(2).and_then(|s| s.parse().ok());
    let text = std::fs::read_to_string(&path).unwrap();
    let mut v = Vec::new();
    let mut t = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let x: Vec<f64> = it.take(3).map(|s| s.parse().unwrap()).collect();
                v.push(DVec3::new(x[0], x[1], x[2]));
            }
            Some("f") => {
                let x: Vec<u32> = it
                    .map(|s| s.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for i in 1..x.len() - 1 {
                    t.push([x[0], x[i], x[i + 1]]);
                }
            }
            _ => {}
        }
    }
    let mesh = Mesh::new(v, t).unwrap();
    let params = Params {
        k,
        ..Params::default()
    };
    let t0 = std::time::Instant::now();
    let seg = segment_with(&mesh, &params, |s| {
        eprintln!(
            "{:?} k={} F={:.4} TOV={:.3} MOV={:.3} t={:.3}",
            s.kind,
            s.k,
            s.f,
            s.tov,
            s.mov,
            t0.elapsed().as_secs_f64()
        )
    })
    .unwrap();
    let mut o: Vec<(f64, usize, f64)> = seg.parts.iter().map(|p| (p.ov, p.samples, p.e)).collect();
    o.sort_by(|a, b| b.0.total_cmp(&a.0));
    eprintln!("top ov: {:?}", &o[..o.len().min(8)]);
    eprintln!(
        "done k={} F={:.4} TOV={:.3} MOV={:.3} samples={} in {:.3}s",
        seg.metrics.k,
        seg.metrics.f,
        seg.metrics.tov,
        seg.metrics.mov,
        seg.metrics.samples,
        t0.elapsed().as_secs_f64()
    );
}
// (appended) nothing
