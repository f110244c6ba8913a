//! `fw-cost`: instructions per step of a configuration given as arguments
//! (`absorber_firmware::cost`; the cost column of docs/accuracy.md).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    absorber_firmware::target::cost_main()
}

#[cfg(not(target_os = "none"))]
fn main() {
    let mut c = absorber_firmware::cost::Config::default();
    for a in std::env::args().skip(1) {
        if let Err(key) = c.set(&a) {
            eprintln!("fw-cost: bad argument `{a}` (key `{key}`)");
            std::process::exit(4);
        }
    }
    let mut out = String::new();
    let code = absorber_firmware::cost::run(&c, &mut out);
    print!("{out}");
    std::process::exit(i32::from(code));
}
