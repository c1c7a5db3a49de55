//! Controller names as data: the registered names (the registry builds
//! exactly these) and the paper's three in table order, which is also the
//! default controller list of a scenario. Kept below the scenario so that a
//! scenario can check its `controllers` without knowing how controllers are
//! built; `registry` tests that it builds every name listed here.

/// The three controllers compared in the paper, in table order.
pub const PAPER_CONTROLLERS: [&str; 3] = ["ranftsmc", "tsm-sta", "ftaftsmc"];

/// Every registered name (with a one-line description).
pub const CONTROLLERS: [(&str, &str); 4] = [
    ("ftaftsmc", "fixed-time adaptive fast terminal SMC with mass adaptation (the paper's controller)"),
    ("ftaftsmc-no-mass", "FTAFTSMC with the mass adaptation of §3.2 switched off (U1 = u1)"),
    ("ranftsmc", "robust adaptive nonsingular fast terminal SMC (Labbadi & Cherkaoui 2020, ref. [19])"),
    ("tsm-sta", "nonsingular terminal sliding surface with super-twisting reaching law (ref. [2])"),
];

/// `Ok(())` for a registered name; otherwise the list of known names.
pub fn check_controller(name: &str) -> Result<(), String> {
    if CONTROLLERS.iter().any(|(n, _)| *n == name) {
        Ok(())
    } else {
        Err(CONTROLLERS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "))
    }
}
