use bvseg_core::*;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let k: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let n: usize = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(15000);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut v = Vec::new();
    let mut t = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let x: Vec<f64> = it.take(3).map(|s| s.parse().unwrap()).collect();
                v.push(glam::DVec3::new(x[0], x[1], x[2]));
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
    let grid = sampling::Grid::from_mesh(&mesh, n).unwrap();
    let solid = partition::Solid::new(grid);
    let (comps, nc) = flooding::solid_components(&solid.grid);
    let p0 = initialization::cvt(&solid, &comps, nc, k, 0);
    for _ in 0..12 {
        let mut p = p0.clone();
        let t0 = std::time::Instant::now();
        let s1 = optimization::lloyd(&solid, &comps, &mut p, None, 100);
        let t1 = t0.elapsed().as_secs_f64();
        let m = optimization::polish(&solid, &mut p, None);
        let t2 = t0.elapsed().as_secs_f64();
        eprintln!(
            "samples {} sweeps {} lloyd {:.1} ms, polish moves {} {:.1} ms, F {:.4} -> {:.4}",
            solid.len(),
            s1,
            t1 * 1e3,
            m,
            (t2 - t1) * 1e3,
            p0.f(),
            p.f()
        );
    }
}
