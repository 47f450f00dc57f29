//! The coverage-guided fuzz binary: `oeg-fuzz TARGET` reads inputs from AFL++ (see `scripts/fuzz.sh`).

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    let Some(target) = oeg_fuzz::Target::from_name(&name) else {
        eprintln!(
            "usage: oeg-fuzz TARGET, one of: {}",
            oeg_fuzz::TARGETS.map(oeg_fuzz::Target::name).join(", ")
        );
        std::process::exit(2);
    };
    afl::fuzz!(|data: &[u8]| {
        oeg_fuzz::run(target, data);
    });
}
