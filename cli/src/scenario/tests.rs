//! The scenario loader's tests: observables, hostile overrides, the exact references
//! and where keys are.

use super::*;

#[test]
fn observables_parse() {
    assert_eq!(Observable::parse("M2"), Ok(Observable::Moment(2.0)));
    assert_eq!(Observable::parse("M1.5"), Ok(Observable::Moment(1.5)));
    assert_eq!(Observable::parse("n3"), Ok(Observable::Density(3)));
    assert_eq!(
        Observable::parse("C(100,200)"),
        Ok(Observable::Concentration(100.0, 200.0))
    );
    assert_eq!(Observable::parse("C[1,2)"), Ok(Observable::Class(1.0, 2.0)));
    assert_eq!(Observable::Class(1.0, 2.5).name(), "C[1,2.5)");
    assert_eq!(Observable::parse("gel"), Ok(Observable::Gel));
    assert_eq!(
        Observable::parse("mean-temperature"),
        Ok(Observable::Named("mean-temperature".into()))
    );
    for bad in [
        "", "M", "Mx", "n0", "n-1", "C(2,1)", "C(0,1)", "C(1)", "C[1,1)", "C[2,1)", "C[1,2]",
        "Foo!", "Minf", "M100",
    ] {
        assert!(Observable::parse(bad).is_err(), "{bad}");
    }
}

use proptest::prelude::*;

const KEYS: &[&str] = &[
    "kernel.kind",
    "kernel.coefficient",
    "kernel.a",
    "kernel.gamma",
    "kernel.temperature",
    "kernel.viscosity",
    "kernel.density",
    "kernel.monomer-diameter",
    "fragmentation.kind",
    "fragmentation.rate",
    "initial.kind",
    "initial.particles",
    "initial.size",
    "initial.mean",
    "initial.median",
    "initial.gsd",
    "initial.resolution",
    "initial.sizes",
    "initial.counts",
    "initial.concentration",
    "scheme.name",
    "scheme.dt",
    "scheme.points",
    "scheme.size-limit",
    "scheme.engine",
    "scheme.randomization",
    "initial.temperature",
    "output.times",
    "output.t-end",
    "output.t-start",
    "output.count",
    "output.spacing",
    "output.observables",
    "output.classes",
    "output.log-axes",
    "run.replicas",
    "run.seed",
    "run.threads",
    "title",
    "source",
    "source.rate",
    "source.kind",
    "source.size",
    "source.mean",
    "source.gsd",
    "sink.rate",
    "sink.exponent",
    "growth.rate",
    "growth.exponent",
    "growth.step",
    "nonsense.key",
];
const VALUES: &[&str] = &[
    "0",
    "1",
    "-1",
    "2",
    "3",
    "0.5",
    "1e308",
    "-1e-308",
    "nan",
    "inf",
    "4096",
    "1000",
    "18446744073709551615",
    "9223372036854775807",
    "\"constant\"",
    "\"additive\"",
    "\"product\"",
    "\"physical\"",
    "\"exponential\"",
    "\"lognormal\"",
    "\"sizes\"",
    "\"counts\"",
    "\"massflow\"",
    "\"lowrank\"",
    "\"rejection\"",
    "\"inverse\"",
    "\"owen\"",
    "\"temperature\"",
    "\"dsmc\"",
    "\"hard-spheres\"",
    "\"log\"",
    "[1, 2, 3]",
    "[0.5, 1.0]",
    "[]",
    "[\"M0\", \"gel\"]",
    "[\"C(1,2)\"]",
    "{}",
    "true",
    "\"x\"",
    "[1.0, 1e300]",
    "[1, 0]",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    /// Random overrides of every key by hostile values on every example never
    /// panic: the loader returns a plan or an error with a message.
    #[test]
    fn overrides_never_panic(
        ex in 0..crate::examples::EXAMPLES.len(),
        sets in prop::collection::vec((0..KEYS.len(), 0..VALUES.len()), 1..5),
        drops in prop::collection::vec(0..KEYS.len(), 0..2),
    ) {
        let (name, text) = crate::examples::EXAMPLES[ex];
        let mut ov = Vec::new();
        for (k, v) in sets {
            let (key, value) = parse_override(&format!("{}={}", KEYS[k], VALUES[v])).unwrap();
            ov.push((key, value));
        }
        let drops: Vec<String> = drops.into_iter().map(|k| KEYS[k].to_string()).collect();
        match load(&Source { name, text, overrides: &ov, drops: &drops }) {
            Ok(plan) => prop_assert!(!plan.times.is_empty() && !plan.observables.is_empty()),
            Err(e) => prop_assert!(!e.message.is_empty()),
        }
    }
}

/// Direct simulation, over counts or over particles, is the Marcus–Lushnikov process:
/// its gel reference for the multiplicative kernel is 1 − t*/t, the mass flow's
/// Flory's 1 − 1/t.
#[test]
fn multiplicative_reference_follows_the_process() {
    let (name, text) = crate::examples::get("multiplicative-gelation").unwrap();
    let gel_at_2 = |scheme: &str| {
        let ov = vec![(
            "scheme.name".to_string(),
            toml::Value::String(scheme.into()),
        )];
        let plan = load(&Source {
            name,
            text,
            overrides: &ov,
            drops: &[],
        })
        .unwrap();
        plan.exact.unwrap().value(&Observable::Gel, 2.0).unwrap()
    };
    let flory = 0.5;
    let ml = 1.0 - coagula_core::exact::dual_time(2.0).unwrap() / 2.0;
    for scheme in ["lowrank", "dsa", "dsa-counts"] {
        approx::assert_relative_eq!(gel_at_2(scheme), ml, max_relative = 1e-12);
    }
    approx::assert_relative_eq!(gel_at_2("mfa"), flory, max_relative = 1e-12);
}

/// `scheme.engine` pins the bucketed engine, and only lowrank takes it.
#[test]
fn engine_key() {
    let (name, text) = crate::examples::get("quickstart-constant").unwrap();
    let with = |scheme: &str, engine: &str| {
        let ov = vec![
            (
                "scheme.name".to_string(),
                toml::Value::String(scheme.into()),
            ),
            (
                "scheme.engine".to_string(),
                toml::Value::String(engine.into()),
            ),
        ];
        load(&Source {
            name,
            text,
            overrides: &ov,
            drops: &[],
        })
    };
    use coagula_core::scheme::facade::BucketMode;
    let plan = with("lowrank", "slots").unwrap();
    assert_eq!(plan.options.engine(), Some(BucketMode::Slots));
    let plan = with("lowrank", "counted").unwrap();
    assert_eq!(plan.options.engine(), Some(BucketMode::Counted));
    assert!(with("lowrank", "alias").is_err());
    let e = with("lowrank-tree", "slots").unwrap_err();
    // core's message, the one C and Python get for the same mistake
    assert!(
        e.message.contains("does not apply to scheme lowrank-tree"),
        "{}",
        e.message
    );
}

/// A named observable parses by its shape; the scheme's entry decides whether it has
/// one by that name (core's list, not the CLI's).
#[test]
fn named_observables_are_the_schemes() {
    let (name, text) = crate::examples::get("quickstart-constant").unwrap();
    let with = |scheme: &str, observable: &str| {
        let ov = vec![
            (
                "scheme.name".to_string(),
                toml::Value::String(scheme.into()),
            ),
            (
                "output.observables".to_string(),
                toml::Value::Array(vec![toml::Value::String(observable.into())]),
            ),
        ];
        load(&Source {
            name,
            text,
            overrides: &ov,
            drops: &[],
        })
    };
    assert!(with("lowrank", "M0").is_ok());
    let e = with("lowrank", "foo").unwrap_err();
    assert!(e.message.contains("named observables"), "{}", e.message);
    let e = with("lowrank", "mean-temperature").unwrap_err();
    assert!(e.message.contains("named observables"), "{}", e.message);
}

#[test]
fn lines_of_keys() {
    let text = "title = \"x\"\n[kernel]\nkind = \"product\"\na = 1.5\n";
    assert_eq!(line_of(text, "kernel.a"), Some(4));
    assert_eq!(line_of(text, "title"), Some(1));
    assert_eq!(line_of(text, "kernel.gamma"), None);
}

/// The CI smoke run of the scenario-parser fuzz target (`fuzz/`): every input of its
/// committed corpus and every reproducer under `fuzz/regressions/` is loaded (or
/// refused with a message) through this parser, as the target does.
#[test]
fn scenario_parser_corpus_and_regressions() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut n = 0;
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join("scenario_parser")) else {
            continue;
        };
        for e in entries.filter_map(|e| e.ok()) {
            let data = std::fs::read(e.path()).unwrap();
            n += 1;
            let Ok(text) = std::str::from_utf8(&data) else {
                continue;
            };
            let (text, overrides) = match text.split_once("\n#--set ") {
                Some((t, o)) => match parse_override(o.trim()) {
                    Ok(kv) => (t, vec![kv]),
                    Err(_) => (t, Vec::new()),
                },
                None => (text, Vec::new()),
            };
            let src = Source {
                name: "fuzz.toml",
                text,
                overrides: &overrides,
                drops: &[],
            };
            if let Err(e) = load(&src) {
                assert!(!e.to_string().is_empty());
            }
        }
    }
    assert!(n >= 10, "{n} inputs");
}

/// `[source]`, `[sink]` and `[growth]`: in simulation units on a size grid; refused
/// with the key where a scheme cannot take them; the citation's old key named.
#[test]
fn processes_tables() {
    let base = crate::examples::get("processes-source-dilution").unwrap().1;
    let plan = |ov: &[&str], drops: &[&str]| {
        let ov: Vec<_> = ov.iter().map(|o| parse_override(o).unwrap()).collect();
        let drops: Vec<String> = drops.iter().map(|d| d.to_string()).collect();
        load(&Source {
            name: "p.toml",
            text: base,
            overrides: &ov,
            drops: &drops,
        })
    };
    let p = plan(&[], &[]).unwrap();
    let procs = p.processes.clone().unwrap();
    assert_eq!(procs.source.unwrap().rate(), 0.5);
    assert_eq!(procs.removal.unwrap().coefficient, 0.25);
    // the closed form of the moment equations: M1 = S/λ + (1 − S/λ) e^{−λt}
    let e = p.exact.unwrap();
    let m1 = e.value(&Observable::Moment(1.0), 4.0).unwrap();
    assert!((m1 - (2.0 - (-1.0f64).exp())).abs() < 1e-12, "{m1}");
    // an exponential start on a grid of 1/64: sizes and rates in grid units
    let p = plan(
        &[
            "initial.kind=\"exponential\"",
            "source.kind=\"exponential\"",
            "source.mean=2.0",
            "sink.exponent=1.0",
            "growth.rate=0.5",
            "growth.exponent=1.0",
        ],
        &["source.size"],
    );
    let p = p.unwrap_or_else(|e| panic!("{e}"));
    let procs = p.processes.unwrap();
    let u = p.size_unit;
    assert_eq!(u, 1.0 / 64.0);
    match procs.source.unwrap().sizes() {
        coagula_core::initial::Distribution::Exponential { mean } => assert_eq!(*mean, 2.0 / u),
        d => panic!("{d:?}"),
    }
    assert_eq!(procs.removal.unwrap().coefficient, 0.25 * u);
    // linear growth dx/dt = 0.5 x: attachment at 0.5 i per grid unit
    assert_eq!(procs.growth.unwrap().coefficient, 0.5);
    for (ov, key) in [
        (&["sink.exponent=2.0"][..], "sink"),
        (
            &["growth.rate=1.0", "scheme.name=\"lowrank-sizes\""][..],
            "growth.step",
        ),
        (&["scheme.name=\"mfa\""][..], "scheme.name"),
        (
            &[
                "scheme.name=\"massflow\"",
                "scheme.dt=0.01",
                "growth.rate=0.5",
                "growth.step=0.05",
            ][..],
            "growth.step",
        ),
        (&["source.kind=\"counts\""][..], "source.kind"),
        (&["source.rate=-1"][..], "source"),
        (&["source.mean=2.0"][..], "source.mean"),
        (&["source.sizes=[1.0, 2.0]"][..], "source.sizes"),
        (&["source.kind=\"sizes\""][..], "source.size"),
        (
            &["source.kind=\"sizes\"", "source.size=1.0"][..],
            "source.size",
        ),
    ] {
        let e = plan(ov, &[])
            .err()
            .unwrap_or_else(|| panic!("{ov:?} accepted"));
        assert!(e.message.contains(key), "{ov:?}: {}", e.message);
    }
    // growth on real sizes by splitting of the step given; the step refused on integer
    // sizes, where growth is attachment
    let p = plan(
        &[
            "scheme.name=\"lowrank-sizes\"",
            "growth.rate=0.5",
            "growth.step=0.05",
        ],
        &[],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.processes.unwrap().growth_step, Some(0.05));
    let e = plan(&["growth.rate=0.5", "growth.step=0.05"], &[])
        .err()
        .unwrap();
    assert!(e.message.contains("growth.step"), "{}", e.message);
    // a listed source: drawn uniformly from the list, its closed form with the list's
    // mean and mean square; not on an integer scheme when a size is not an integer
    let p = plan(
        &["source.kind=\"sizes\"", "source.sizes=[1.0, 3.0, 3.0]"],
        &["source.size"],
    )
    .unwrap();
    match p.processes.unwrap().source.unwrap().sizes() {
        coagula_core::initial::Distribution::Sizes(x) => assert_eq!(x, &[1.0, 3.0, 3.0]),
        d => panic!("{d:?}"),
    }
    // M1 = S μ1/λ + (1 − S μ1/λ) e^{−λt}, μ1 = 7/3
    let m1 = p
        .exact
        .unwrap()
        .value(&Observable::Moment(1.0), 4.0)
        .unwrap();
    let q = 0.5 * 7.0 / 3.0 / 0.25;
    assert!(
        (m1 - (q + (1.0 - q) * (-1.0f64).exp())).abs() < 1e-12,
        "{m1}"
    );
    let p = plan(
        &["source.kind=\"sizes\"", "source.sizes=[1.5, 3.0]"],
        &["source.size"],
    )
    .unwrap();
    assert!(p.exact.is_none());
    // a schedule: S(t) piecewise, no closed form; times and rates come together
    let p = plan(&["source.times=[1.0, 2.0]", "source.rates=[0.0, 3.0]"], &[]).unwrap();
    let q = p.processes.unwrap().source.unwrap();
    assert_eq!(
        (q.rate_at(0.5), q.rate_at(1.5), q.rate_at(2.5)),
        (0.5, 0.0, 3.0)
    );
    assert!(p.exact.is_none());
    for (ov, key) in [
        (&["source.times=[1.0]"][..], "source.rates"),
        (&["source.rates=[1.0]"][..], "source.times"),
        (
            &["source.times=[2.0, 1.0]", "source.rates=[1.0, 1.0]"][..],
            "source.times",
        ),
    ] {
        let e = plan(ov, &[])
            .err()
            .unwrap_or_else(|| panic!("{ov:?} accepted"));
        assert!(e.message.contains(key), "{ov:?}: {}", e.message);
    }
    let old = base
        .replace("reference = ", "source = ")
        .replace("[source]", "[inflow]");
    let e = load(&Source {
        name: "old.toml",
        text: &old,
        overrides: &[],
        drops: &[],
    })
    .err()
    .unwrap();
    assert!(e.message.contains("reference"), "{}", e.message);
}
