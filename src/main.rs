use uncoil::model::{Model, Phase};
use uncoil::scene::Scene;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let scene = Scene::from_file(&path).unwrap();
    let mut m = Model::new(&scene);
    if std::env::var("NOSHED").is_ok() { m.set_shedding(false); }
    let (k0, p0) = m.energy();
    let e0 = k0 + p0;
    println!("links {} E0 {e0}", m.link_count());
    let t0 = std::time::Instant::now();
    let mut n = 0u64;
    let mut next = 0.0;
    loop {
        let o = m.step();
        n += 1;
        if o.t_s >= next || o.phase == Phase::Done {
            next += if o.t_s > 2.0 && o.t_s < 2.3 { 0.005 } else { 0.05 };
            println!("t {:.3} f {:.4} x {:.4} w {:.2} K {:.4} P {:.4} lost {:.4} [{:.4} {:.4} {:.4} {:.4}] N {:.3} F {:.3} bodies {} gap {:.2e} pen {:.2e} dt {:.1e}",
              o.t_s, o.laid_fraction, o.x_m, o.omega_rad_s, o.kinetic_j, o.potential_j, e0 - o.kinetic_j - o.potential_j,
              o.ledger.step_j, o.ledger.detach_j, o.ledger.freeze_j, o.ledger.bang_j, o.normal_n, o.friction_n, o.active_bodies, o.max_joint_gap_m, o.max_penetration_m, o.dt_s);
        }
        if o.phase == Phase::Done || o.t_s > scene.stop.max_time_s { break; }
    }
    println!("steps {n} wall {:?}", t0.elapsed());
}
