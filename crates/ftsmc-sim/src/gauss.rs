//! Normal draws whose bits do not depend on the platform's C library:
//! [`standard_normal`] (`N(0, 1)`), [`Normal`] (`N(μ, σ²)`) and
//! [`LogNormal`] (`exp(N(μ, σ²))`).
//!
//! The standard normal is the ZIGNOR ziggurat of Doornik (2005), "An
//! Improved Ziggurat Method to Generate Normal Random Samples" (Nuffield
//! College, Oxford), a variant of Marsaglia & Tsang (2000), "The Ziggurat
//! Method for Generating Random Variables", J. Stat. Softw. 5(8): 256
//! layers of equal area [`ZIG_V`] under `f(x) = exp(−x²/2)`, the base
//! layer's edge at [`ZIG_R`]. It is the algorithm of the Rust `rand_distr`
//! crate's `StandardNormal` (0.6), tables included, and reads the
//! generator's words exactly as it does: one `u64` per attempt (its low 8
//! bits pick the layer, its high 52 bits the abscissa), one more per wedge
//! test (53-bit uniform in `[0, 1)`) and two per tail attempt (52-bit
//! uniforms in `(0, 1)`). The difference is where `exp` (the wedge, and
//! every log-normal draw) and `ln` (the tail) come from: here always
//! [`ftsmc_core::math`] (the pure-Rust `libm` crate, FreeBSD msun's
//! algorithms). `rand_distr`'s standard normal calls `f64::exp` and
//! `f64::ln`, i.e. the platform's C library (glibc, macOS's libm, musl …,
//! which need not agree in the last bit). Its `LogNormal` calls
//! `num-traits`' `Float::exp`: the `libm` crate, unless any package of the
//! build enables `num-traits`' `std` feature, and then the C library's; the
//! Python module (through `numpy`), `cargo build --workspace` and the test
//! builds enable it and the `ftsmc` binary built alone does not, so the same
//! seed drew different log-normals depending on what was built together.
//! With the platform's functions substituted, the draws here are
//! `rand_distr`'s bit for bit (tested). About 1.5 % of draws reach the
//! wedge and 0.026 % the tail.
//!
//! Against glibc 2.36 (x86-64, FMA) `libm` differs by one unit in the last
//! place for about 9 % of the wedge's `exp` arguments and 7 % of the
//! tail's `ln` arguments; on 10.2 million standard normal draws that is
//! 16 tail draws moved by one unit in the last place and no other draw (a
//! wedge draw moves only if `exp`'s last bit flips the acceptance test),
//! and one log-normal draw in about 20 (`σ = 0.1`) against glibc's `exp`.

use ftsmc_core::math;
use rand::Rng;

/// Abscissa `r = x₁` of the base layer's edge (the tail starts there),
/// Doornik (2005) for 256 layers (`dR`), as in `rand_distr`.
pub const ZIG_R: f64 = 3.654_152_885_361_009;

/// Area `v` of each of the 256 layers under `f(x) = exp(−x²/2)`, Doornik
/// (2005) for 256 layers (`dV`): `v = r f(r) + ∫_r^∞ f`.
pub const ZIG_V: f64 = 0.00492867323399;

/// Layer edges `x_i`, `i = 0..=256`: `x₀ = v / f(r)` (the base layer as a
/// box of area `v`), `x₁ = r`, `x_{i+1} = f⁻¹(v / x_i + f(x_i))` with
/// `f⁻¹(y) = √(−2 ln y)` for `i = 1..=254`, and `x₂₅₆ = 0` (Doornik 2005,
/// `zigNorInit`). Each value is the recurrence in `f64` with correctly
/// rounded `exp`, `ln` and `sqrt`, rounded to 18 decimal places, as the
/// tables of the Rust `rand` project (`ziggurat_tables.py`) were
/// published; `tests::tables_follow_the_recurrence` re-runs it.
#[rustfmt::skip]
static ZIG_X: [f64; 257] = [
    3.91075795953709, 3.654152885361009, 3.4492782985609645, 3.320244733839166,
    3.224575052047029, 3.14788928951715, 3.083526132001233, 3.0278377917686354,
    2.978603279880845, 2.9343668672078542, 2.894121053612348, 2.8571387308721325,
    2.822877396825325, 2.7909211740007858, 2.7609440052788226, 2.732685359042827,
    2.705933656121858, 2.680514643284522, 2.6562830375755024, 2.6331163936303246,
    2.6109105184875485, 2.589575986706995, 2.5690354526805366, 2.5492215503234608,
    2.530075232158517, 2.5115444416253423, 2.4935830412696807, 2.4761499396691433,
    2.4592083743333113, 2.4427253181989568, 2.426670984935726, 2.4110184138996855,
    2.3957431197804806, 2.380822795170626, 2.3662370567158186, 2.35196722737766,
    2.3379961487950314, 2.324308018869623, 2.31088825059985, 2.2977233489013296,
    2.284800802722946, 2.272108990226824, 2.259637095172218, 2.2473750329458078,
    2.235313384928328, 2.2234433400909057, 2.2117566428825444, 2.200245546609648,
    2.1889027716247207, 2.1777214677386416, 2.166695180352646, 2.1558178198750633,
    2.1450836340462036, 2.13448718284432, 2.1240233156878157, 2.113687150684934,
    2.103474055713147, 2.0933796311370503, 2.083399693996552, 2.0735302635169788,
    2.0637675478099564, 2.054107931648865, 2.044547965215733, 2.0350843537278087,
    2.025713947862033, 2.0164337349043717, 2.007240830558685, 1.9981324713565642,
    1.9891060076155713, 1.9801588968985984, 1.9712886979317696, 1.962493064942462,
    1.953769742382734, 1.945116560006754, 1.936531428273759, 1.9280123340507183,
    1.9195573365912288, 1.9111645637692822, 1.9028322085484464, 1.89455852566871,
    1.8863418285347764, 1.8781804862909777, 1.8700729210692368, 1.8620176053976323,
    1.8540130597581481, 1.8460578502831198, 1.8381505865807286, 1.8302899196806666,
    1.8224745400917832, 1.8147031759641676, 1.8069745913486934, 1.7992875845475802,
    1.79164098655001, 1.7840336595472763, 1.776464495522345, 1.768932414909078,
    1.7614363653167067, 1.753975320315455, 1.746548278279493, 1.739154261283669,
    1.7317923140507072, 1.7244615029457757, 1.7171609150155407, 1.709889657069006,
    1.702646854797614, 1.6954316519322385, 1.6882432094348587, 1.6810807047228233,
    1.6739433309237604, 1.6668302961592867, 1.6597408228557895, 1.6526741470806485,
    1.6456295179023603, 1.6386061967731111, 1.631603456932422, 1.6246205828305684,
    1.6176568695705342, 1.6107116223673337, 1.603784156023583, 1.5968737944202613,
    1.5899798700216485, 1.5831017233934714, 1.5762387027333329, 1.5693901634125345,
    1.5625554675284397, 1.555733983466555, 1.5489250854715355, 1.5421281532263476,
    1.5353425714388431, 1.5285677294350246, 1.521803020758293, 1.5150478427739924,
    1.508301596278572, 1.5015636851127065, 1.4948335157777184, 1.4881104970546544,
    1.4813940396253757, 1.4746835556950255, 1.467978458615231, 1.4612781625074078,
    1.4545820818855233, 1.4478896312776697, 1.441200224845798, 1.4345132760029464,
    1.4278281970272904, 1.4211443986723231, 1.4144612897724647, 1.4077782768433715,
    1.4010947636762026, 1.3944101509250713, 1.3877238356868846, 1.381035211072742,
    1.3743436657700305, 1.367648583594318, 1.3609493430301018, 1.3542453167594306,
    1.3475358711773593, 1.3408203658931521, 1.3340981532160836, 1.3273685776246247,
    1.32063097521773, 1.313884673146869, 1.3071289890273539, 1.3003632303274337,
    1.2935866937335176, 1.2867986644897864, 1.2799984157103332, 1.2731852076618437,
    1.2663582870146883, 1.2595168860601442, 1.2526602218912979, 1.245787495544998,
    1.2388978911020274, 1.231990574742445, 1.225064693752808, 1.2181193754817266,
    1.2111537262399112, 1.2041668301405601, 1.197157747875586, 1.1901255154228016,
    1.1830691426787607, 1.1759876120114898, 1.1688798767268338, 1.1617448594415742,
    1.1545814503558518, 1.1473885054167339, 1.1401648443639958, 1.132909248648337,
    1.1256204592112944, 1.118297174115063, 1.1109380460092495, 1.1035416794202682,
    1.0961066278476035, 1.0886313906495142, 1.0811144096988894, 1.0735540657878717,
    1.0659486747575067, 1.0582964833260065, 1.0505956645862071, 1.0428443131393705,
    1.0350404398286053, 1.0271819660307513, 1.0192667174605292, 1.0112924174349784,
    1.0032566795395914, 0.9951569996299431, 0.9869907470938463, 0.9787551552889378,
    0.9704473110588646, 0.9620641432176052, 0.9536024098755727, 0.9450586844625711,
    0.9364293402808969, 0.9277105333962348, 0.918898183643735, 0.909987953490769,
    0.9009752244551745, 0.8918550707267924, 0.8826222295789101, 0.8732710680824946,
    0.8637955455468269, 0.8541891710015606, 0.8444449549024237, 0.8345553540795188,
    0.8245122087452886, 0.8143066701280643, 0.8039291169826649, 0.7933690588331528,
    0.7826150232995888, 0.7716544242167394, 0.7604734064220832, 0.7490566620095817,
    0.7373872114258386, 0.7254461409013035, 0.7132122851820227, 0.7006618410975844,
    0.6877678927862577, 0.6744998228274365, 0.660822574234206, 0.6466957148843889,
    0.6320722363750246, 0.6168969899962355, 0.6011046177439404, 0.5846167660937223,
    0.567338257040473, 0.5491517023130268, 0.5299097206464951, 0.5094233295859334,
    0.48744396612175434, 0.46363433677176324, 0.43751840218666266, 0.40838913458800075,
    0.3751213328504657, 0.33573751918045946, 0.2861745917472605, 0.2152418959132738,
    0.0,
];

/// `f(x_i) = exp(−x_i²/2)` for `i = 0..=255` ([`ZIG_X`]) and `f(0) = 1`
/// at `i = 256`, each the correctly rounded `exp` of the `f64` argument
/// `−x_i·x_i/2`, rounded to 18 decimal places like [`ZIG_X`].
#[rustfmt::skip]
static ZIG_F: [f64; 257] = [
    0.000477467764586655, 0.001260285930498598, 0.002609072746106363, 0.004037972593371872,
    0.005522403299264754, 0.00705087547139211, 0.008616582769422917, 0.0102149714397311,
    0.011842757857943104, 0.013497450601780807, 0.015177088307982072, 0.01688008315259584,
    0.01860512127578335, 0.020351096230109354, 0.022117062707379922, 0.023902203305873237,
    0.025705804008632656, 0.027527235669693315, 0.02936593975823011, 0.03122141719202369,
    0.0330932194586887, 0.03498094146183307, 0.03688421568869115, 0.03880270740465692,
    0.04073611065607875, 0.04268414491661938, 0.044646552251446536, 0.046623094902089664,
    0.048613553216035145, 0.05061772386112179, 0.05263541827697365, 0.054666461325077916,
    0.05671069010639947, 0.058767952921137984, 0.060838108349751806, 0.06292102443797785,
    0.06501657797147044, 0.06712465382802399, 0.06924514439725027, 0.07137794905914197,
    0.07352297371424099, 0.07568013035919496, 0.07784933670237221, 0.08003051581494751,
    0.08222359581349568, 0.08442850957065466, 0.08664519445086778, 0.08887359206859423,
    0.09111364806670073, 0.09336531191302662, 0.09562853671335333, 0.09790327903921563,
    0.10018949876917202, 0.10248715894230627, 0.10479622562286706, 0.10711666777507288,
    0.10944845714721002, 0.11179156816424558, 0.11414597782825521, 0.11651166562603701,
    0.1188886134433457, 0.12127680548523544, 0.1236762282020514, 0.12608687022065035,
    0.12850872228047364, 0.13094177717412817, 0.13338602969216284, 0.13584147657175735,
    0.13830811644906432, 0.1407859498149683, 0.14327497897404712, 0.14577520800653793,
    0.14828664273312872, 0.15080929068241017, 0.15334316106083767, 0.15588826472506456,
    0.15844461415652022, 0.16101222343811766, 0.16359110823298295, 0.16618128576511007,
    0.16878277480185033, 0.17139559563815562, 0.17401977008249936, 0.17665532144440665,
    0.1793022745235304, 0.1819606556002165, 0.18463049242750454, 0.18731181422451693,
    0.19000465167119307, 0.1927090369043288, 0.1954250035148856, 0.1981525865465381,
    0.20089182249543133, 0.2036427493111215, 0.2064054063986793, 0.20917983462193565,
    0.21196607630785294, 0.2147641752520085, 0.21757417672517837, 0.2203961274810116,
    0.2232300757647896, 0.22607607132326488, 0.22893416541557748, 0.23180441082524852,
    0.2346868618732527, 0.23758157443217368, 0.2404886059414491, 0.243408015423712,
    0.24633986350223877, 0.2492842124195167, 0.25224112605694377, 0.25521066995567715,
    0.258192911338648, 0.2611879191337637, 0.26419576399831757, 0.26721651834463184,
    0.27025025636696, 0.2732970540696758, 0.27635698929678126, 0.2794301417627653,
    0.2825165930848494, 0.2856164268166581, 0.28872972848335393, 0.291856585618281,
    0.29499708780116257, 0.29815132669790134, 0.3013193961020341, 0.3045013919778963,
    0.30769741250555377, 0.3109075581275637, 0.31413193159763014, 0.3173706380312224,
    0.32062378495823013, 0.323891482377732, 0.3271738428149586, 0.3304709813805371,
    0.3337830158321085, 0.3371100666384128, 0.34045225704594545, 0.34380971314829134,
    0.3471825639582515, 0.3505709414828812, 0.35397498080156925, 0.3573948201472905,
    0.36083060099117575, 0.3642824681305496, 0.3677505697805962, 0.37123505766982134,
    0.3747360871394914, 0.3782538172472381, 0.38178841087503135, 0.38534003484173396,
    0.3889088600204646, 0.39249506146101076, 0.3960988185175471, 0.39972031498193167,
    0.4033597392228689, 0.40701728433124795, 0.4106931482719832, 0.4143875340427068,
    0.4181006498396846, 0.4218327092313533, 0.4255839313399006, 0.4293545410313415,
    0.43314476911457406, 0.4369548525499293, 0.4407850346677699, 0.44463556539772775,
    0.44850670150921407, 0.4523987068638825, 0.45631185268077357, 0.4602464178149235,
    0.46420268905027884, 0.46818096140782217, 0.47218153846988326, 0.4762047327216838,
    0.4802508659112497, 0.4843202694289116, 0.48841328470771206, 0.49253026364614866,
    0.4966715690547963, 0.5008375751284821, 0.5050286679458288, 0.5092452459981361,
    0.513487720749743, 0.5177565172322006, 0.5220520746747949, 0.5263748471741867,
    0.5307253044061939, 0.5351039323830196, 0.5395112342595446, 0.5439477311926499,
    0.5484139632579211, 0.5529104904285199, 0.5574378936214863, 0.5619967758172779,
    0.5665877632589518, 0.571211506738075, 0.5758686829752105, 0.5805599961036835,
    0.5852861792663003, 0.590047996335792, 0.5948462437709913, 0.5996817526221677,
    0.6045553907005495, 0.6094680649288954, 0.6144207238920768, 0.6194143606090392,
    0.6244500155502742, 0.6295287799281283, 0.63465179929096, 0.639820277456439,
    0.6450354808242519, 0.6502987431142946, 0.6556114705832247, 0.6609751477802414,
    0.6663913439123806, 0.6718617199007664, 0.6773880362225131, 0.6829721616487914,
    0.6886160830085271, 0.6943219161300326, 0.7000919181404901, 0.7059285013367974,
    0.7118342488823585, 0.7178119326349014, 0.7238645334728816, 0.7299952645658024,
    0.7362075981312667, 0.7425052963446362, 0.7488924472237267, 0.7553735065117545,
    0.7619533468415465, 0.7686373158033348, 0.7754313049861383, 0.7823418326598619,
    0.7893761435711986, 0.7965423304282546, 0.8038494831763895, 0.8113078743182199,
    0.8189291916094148, 0.8267268339520942, 0.8347162929929304, 0.8429156531184411,
    0.8513462584651237, 0.8600336212030086, 0.8690086880437932, 0.8783096558161468,
    0.8879846607633999, 0.898095921906304, 0.9087264400605629, 0.9199915050483602,
    0.9320600759689902, 0.945198953453078, 0.9598790918124159, 0.9771017012827313,
    1.0,
];

/// `2^-53`: the step of the 53-bit uniforms of the wedge test.
const TWO_POW_M53: f64 = 1.0 / (1u64 << 53) as f64;

/// One standard normal draw `z ~ N(0, 1)` from `rng`: the ZIGNOR ziggurat
/// (module docs) of `rand_distr::StandardNormal` (0.6), reading the same
/// words of the generator, with `exp` and `ln` from [`ftsmc_core::math`].
///
/// An attempt reads one `u64` `b`: layer `i = b & 0xff`, `u ∈ [−1, 1)`
/// from the high 52 bits (`1.b₆₃…b₁₂ × 2 − 3`), `x = u x_i`; `x` is the
/// draw when `|x| < x_{i+1}` (about 98.5 % of attempts, the inlined fast
/// path). Otherwise the base layer (`i = 0`) samples the tail beyond `r`
/// (`tail`: `x = ln U₁ / r`, `y = ln U₂` until `−2y ≥ x²`, `±(r − x)`) and
/// the other layers accept `x` when `f_{i+1} + (f_i − f_{i+1}) U <
/// exp(−x²/2)`, else a new attempt (`rest`, out of line).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    ziggurat(rng, math::exp, math::ln)
}

/// [`standard_normal`] with the `exp` and `ln` given: `math::exp` and
/// `math::ln` for the draws, `f64::exp` and `f64::ln` (the platform's) in
/// the tests that compare the algorithm draw for draw with `rand_distr`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn ziggurat<R, E, L>(rng: &mut R, exp: E, ln: L) -> f64
where
    R: Rng + ?Sized,
    E: Fn(f64) -> f64,
    L: Fn(f64) -> f64,
{
    let (i, u, x) = attempt(rng.next_u64());
    if x.abs() < ZIG_X[i + 1] {
        return x;
    }
    rest(rng, i, u, x, exp, ln)
}

/// Layer `i`, `u ∈ [−1, 1)` and `x = u x_i` of one attempt's word `bits`:
/// the low 8 bits are `i`; the high 52 bits are the mantissa of a double
/// in `[2, 4)` (exponent 1), minus 3 (as `rand`'s `into_float_with_exponent(1) - 3.0`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn attempt(bits: u64) -> (usize, f64, f64) {
    const EXPONENT_ONE: u64 = (1023 + 1) << 52;
    let i = (bits & 0xff) as usize;
    let u = f64::from_bits((bits >> 12) | EXPONENT_ONE) - 3.0;
    (i, u, u * ZIG_X[i])
}

/// The slow part of [`standard_normal`], from an attempt `(i, u, x)` that
/// fell outside layer `i`'s inner box: the tail for `i = 0`, else the
/// wedge test, and new attempts until one is accepted.
#[cold]
#[inline(never)]
fn rest<R, E, L>(rng: &mut R, mut i: usize, mut u: f64, mut x: f64, exp: E, ln: L) -> f64
where
    R: Rng + ?Sized,
    E: Fn(f64) -> f64,
    L: Fn(f64) -> f64,
{
    loop {
        if i == 0 {
            return tail(rng, u, ln);
        }
        // `rand`'s `StandardUniform` f64: the high 53 bits times 2⁻⁵³.
        let uniform = (rng.next_u64() >> 11) as f64 * TWO_POW_M53;
        // `-x * x / 2.0` as rand_distr writes it: the same argument bits.
        if ZIG_F[i + 1] + (ZIG_F[i] - ZIG_F[i + 1]) * uniform < exp(-x * x / 2.0) {
            return x;
        }
        (i, u, x) = attempt(rng.next_u64());
        if x.abs() < ZIG_X[i + 1] {
            return x;
        }
    }
}

/// A draw from the tail `|z| > r` on the side of `u`'s sign (Marsaglia
/// 1964, "Generating a variable from the tail of the normal
/// distribution", Technometrics 6(1)): `x = ln U₁ / r`, `y = ln U₂` with
/// `U₁, U₂ ∈ (0, 1)` until `−2y ≥ x²`; the draw is `±(r − x)`.
fn tail<R: Rng + ?Sized>(rng: &mut R, u: f64, ln: impl Fn(f64) -> f64) -> f64 {
    loop {
        let x = ln(open01(rng)) / ZIG_R;
        let y = ln(open01(rng));
        if -2.0 * y >= x * x {
            return if u < 0.0 { x - ZIG_R } else { ZIG_R - x };
        }
    }
}

/// `rand`'s `Open01` f64: the high 52 bits of a `u64` as the mantissa of a
/// double in `[1, 2)`, minus `1 − 2⁻⁵³`: a uniform in `(0, 1)`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn open01<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    const EXPONENT_ZERO: u64 = 1023 << 52;
    f64::from_bits((rng.next_u64() >> 12) | EXPONENT_ZERO) - (1.0 - f64::EPSILON / 2.0)
}

/// Why a [`Normal`] or [`LogNormal`] cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum GaussError {
    /// The mean (or `μ` of a log-normal) is infinite or NaN.
    #[error("the mean must be a finite number, got {0}")]
    Mean(f64),
    /// The standard deviation (or `σ` of a log-normal) is negative,
    /// infinite or NaN.
    #[error("the standard deviation must be a finite number >= 0, got {0}")]
    StdDev(f64),
}

/// The normal distribution `N(μ, σ²)`: `μ + σ z` with `z` from
/// [`standard_normal`] (one standard draw per draw, as `rand_distr::Normal`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normal {
    mean: f64,
    std_dev: f64,
}

impl Normal {
    /// `N(mean, std_dev²)`; `mean` finite, `std_dev` finite and `>= 0`
    /// (same unit as `mean`).
    pub fn new(mean: f64, std_dev: f64) -> Result<Self, GaussError> {
        if !mean.is_finite() {
            return Err(GaussError::Mean(mean));
        }
        if !(std_dev.is_finite() && std_dev >= 0.0) {
            return Err(GaussError::StdDev(std_dev));
        }
        Ok(Self { mean, std_dev })
    }

    /// The mean `μ`.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The standard deviation `σ`.
    pub fn std_dev(&self) -> f64 {
        self.std_dev
    }

    /// One draw `μ + σ z`, `z ~ N(0, 1)`.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.mean + self.std_dev * standard_normal(rng)
    }
}

/// The log-normal distribution: `exp(X)` with `X ~ N(μ, σ²)` ([`Normal`]),
/// `exp` from [`ftsmc_core::math`] on every draw (`rand_distr::LogNormal`
/// calls the C library's when `num-traits`' `std` feature is on; module
/// docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogNormal {
    normal: Normal,
}

impl LogNormal {
    /// `exp(N(mu, sigma²))`: `mu` and `sigma` are the mean and standard
    /// deviation of the logarithm (dimensionless, natural log); `mu`
    /// finite, `sigma` finite and `>= 0`.
    pub fn new(mu: f64, sigma: f64) -> Result<Self, GaussError> {
        Ok(Self { normal: Normal::new(mu, sigma)? })
    }

    /// One draw `exp(μ + σ z)`, `z ~ N(0, 1)`.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        math::exp(self.normal.sample(rng))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::convert::Infallible;
    use rand::TryRng;

    use crate::rng::chacha_stream as generator;

    /// A generator serving given `u64` words in order (then zeros).
    struct Words {
        words: Vec<u64>,
        next: usize,
    }

    impl Words {
        fn new(words: &[u64]) -> Self {
            Self { words: words.to_vec(), next: 0 }
        }
    }

    impl TryRng for Words {
        type Error = Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Infallible> {
            Ok(self.try_next_u64()? as u32)
        }
        fn try_next_u64(&mut self) -> Result<u64, Infallible> {
            let w = self.words.get(self.next).copied().unwrap_or(0);
            self.next += 1;
            Ok(w)
        }
        fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
            for b in dst {
                *b = self.try_next_u64()? as u8;
            }
            Ok(())
        }
    }

    /// The attempt word of layer `i` whose `u` is `u` (`u` in `[−1, 1)`
    /// with at most 52 fraction bits after adding 3).
    fn word(i: usize, u: f64) -> u64 {
        let bits = (u + 3.0).to_bits() & ((1u64 << 52) - 1);
        (bits << 12) | i as u64
    }

    /// Which part of the ziggurat the first attempt of a draw starting
    /// with word `bits` takes.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Part {
        Box,
        Wedge,
        Tail,
    }

    fn part(bits: u64) -> Part {
        let (i, _, x) = attempt(bits);
        if x.abs() < ZIG_X[i + 1] {
            Part::Box
        } else if i == 0 {
            Part::Tail
        } else {
            Part::Wedge
        }
    }

    /// The platform's `exp` and `ln` (`f64::exp`, `f64::ln`): what
    /// `rand_distr` calls in the tests (its dev-dependency enables
    /// `std_math`), for the draw-for-draw comparisons.
    #[allow(clippy::disallowed_methods)] // the platform's exp, on purpose
    fn platform_exp(x: f64) -> f64 {
        x.exp()
    }

    #[allow(clippy::disallowed_methods)] // the platform's ln, on purpose
    fn platform_ln(x: f64) -> f64 {
        x.ln()
    }

    /// The ziggurat with the platform's `exp` and `ln`, as `rand_distr`.
    fn ziggurat_platform<R: Rng + ?Sized>(rng: &mut R) -> f64 {
        ziggurat(rng, platform_exp, platform_ln)
    }

    /// `b − a` in units in the last place (same sign, finite).
    fn ulps(a: f64, b: f64) -> i64 {
        b.to_bits() as i64 - a.to_bits() as i64
    }

    // ---- double-double arithmetic for correctly rounded exp and ln -----

    /// `a + b` exactly as `(sum, error)` (Knuth's two-sum).
    fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    /// `a b` exactly as `(product, error)` (Dekker's split product, no FMA).
    fn two_prod(a: f64, b: f64) -> (f64, f64) {
        fn split(a: f64) -> (f64, f64) {
            let c = 134_217_729.0 * a; // 2^27 + 1
            let hi = c - (c - a);
            (hi, a - hi)
        }
        let p = a * b;
        let ((ah, al), (bh, bl)) = (split(a), split(b));
        (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
    }

    fn dd_add(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
        let (s, e) = two_sum(a.0, b.0);
        two_sum(s, e + a.1 + b.1)
    }

    fn dd_mul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
        let (p, e) = two_prod(a.0, b.0);
        two_sum(p, e + (a.0 * b.1 + a.1 * b.0))
    }

    /// `eᵃ` in double-double, ~2⁻⁹⁵ relative for `|a| ≤ 10`: `e^(a/2¹⁰)`
    /// by 14 terms of its Taylor series, squared ten times.
    fn exp_dd(a: f64) -> (f64, f64) {
        let r = (a / 1024.0, 0.0); // exact: a power-of-two scaling
        let mut term = (1.0, 0.0);
        let mut sum = (1.0, 0.0);
        for k in 1..=14 {
            term = dd_mul(term, r);
            let q = term.0 / k as f64;
            let (p, e) = two_prod(q, k as f64);
            term = two_sum(q, ((term.0 - p) - e + term.1) / k as f64);
            sum = dd_add(sum, term);
        }
        for _ in 0..10 {
            sum = dd_mul(sum, sum);
        }
        sum
    }

    /// `eᵃ` correctly rounded (up to ties closer than 2⁻⁹⁰).
    fn exp_cr(a: f64) -> f64 {
        let (hi, lo) = exp_dd(a);
        hi + lo
    }

    /// `ln t` correctly rounded for `t ∈ [e⁻¹⁰, 1]`: one Newton step
    /// `y + (t e⁻ʸ − 1)` from `libm`'s `y`, in double-double.
    fn ln_cr(t: f64) -> f64 {
        let y = math::ln(t);
        let r = dd_add(dd_mul((t, 0.0), exp_dd(-y)), (-1.0, 0.0));
        // ln(1 + r) = r − r²/2 (|r| < 2⁻⁵⁰, the rest is below 2⁻¹⁵⁰).
        let r = dd_add(r, (-r.0 * r.0 / 2.0, 0.0));
        let (hi, lo) = dd_add((y, 0.0), r);
        hi + lo
    }

    /// `v` rounded to 18 decimal places (the published tables' format).
    fn to_18_places(v: f64) -> f64 {
        format!("{v:.18}").parse().expect("a decimal parses")
    }

    /// The tables are the recurrence of their docs with correctly rounded
    /// `exp` and `ln` (double-double) and `sqrt`, every value rounded to
    /// 18 decimal places. `libm`'s `exp` of the table's own arguments is
    /// at most one unit in the last place off `f(x_i)` (before the
    /// decimal rounding); the test prints where.
    #[test]
    fn tables_follow_the_recurrence() {
        let f = |x: f64| exp_cr(-x * x / 2.0);
        let mut x = [0.0f64; 257];
        x[0] = ZIG_V / f(ZIG_R);
        x[1] = ZIG_R;
        for i in 2..256 {
            x[i] = math::sqrt(-2.0 * ln_cr(ZIG_V / x[i - 1] + f(x[i - 1])));
        }
        for i in 0..257 {
            assert_eq!(to_18_places(x[i]).to_bits(), ZIG_X[i].to_bits(), "x[{i}] = {:e}", x[i]);
        }
        let mut libm_off = Vec::new();
        for i in 0..257 {
            let exact = if i == 256 { 1.0 } else { f(x[i]) };
            assert_eq!(to_18_places(exact).to_bits(), ZIG_F[i].to_bits(), "f[{i}]");
            if i < 256 {
                let libm = math::exp(-x[i] * x[i] / 2.0);
                assert!(ulps(exact, libm).abs() <= 1, "f[{i}]: libm {libm:e} against {exact:e}");
                if libm != exact {
                    libm_off.push(i);
                }
            }
        }
        println!("f(x_i) where libm's exp is one ulp off the correctly rounded value: i = {libm_off:?}");
    }

    /// Every layer edge is `rand_distr`'s: the attempt `u = ±½` in layer
    /// `i < 255` returns `±x_i / 2` exactly, read back from both samplers;
    /// layer 255 (inner box empty, `x₂₅₆ = 0`) through its wedge with the
    /// largest uniform, which accepts.
    #[test]
    fn layer_edges_are_rand_distrs() {
        use rand_distr::Distribution as _;
        for i in 0..256 {
            for u in [0.5, -0.5] {
                let words = [word(i, u), u64::MAX];
                let theirs: f64 = rand_distr::StandardNormal.sample(&mut Words::new(&words));
                let ours = standard_normal(&mut Words::new(&words));
                assert_eq!(ours.to_bits(), theirs.to_bits(), "layer {i}, u = {u}");
                assert_eq!(ours.to_bits(), (u * ZIG_X[i]).to_bits(), "layer {i}, u = {u}");
            }
        }
    }

    /// The wedge test (with the platform's `exp`, as `rand_distr`) accepts
    /// exactly the uniforms `rand_distr`'s does: in every layer `1..=254`,
    /// at an abscissa mid-wedge, the smallest 53-bit uniform that accepts
    /// (found by bisection: the left side `f_{i+1} + (f_i − f_{i+1}) U`
    /// falls as `U` grows) is the same for both, so `f_i` and `f_{i+1}`
    /// decide alike. A rejected attempt is followed by a sentinel attempt
    /// in the box of layer 100.
    #[test]
    fn wedge_thresholds_are_rand_distrs() {
        use rand_distr::Distribution as _;
        let sentinel = word(100, 0.25);
        let accepts = |ours: bool, i: usize, u: f64, v: u64| {
            let words = [word(i, u), v << 11, sentinel];
            let z: f64 = if ours {
                ziggurat_platform(&mut Words::new(&words))
            } else {
                rand_distr::StandardNormal.sample(&mut Words::new(&words))
            };
            z.to_bits() != (0.25 * ZIG_X[100]).to_bits()
        };
        let top = (1u64 << 53) - 1;
        for i in 1..=254 {
            // A representable u whose x lies mid-wedge.
            let u = attempt(word(i, (ZIG_X[i] + ZIG_X[i + 1]) / (2.0 * ZIG_X[i]))).1;
            assert!(u * ZIG_X[i] > ZIG_X[i + 1], "layer {i}: mid-wedge");
            let threshold = |ours: bool| {
                // Rejects at lo, accepts at hi.
                assert!(!accepts(ours, i, u, 0) && accepts(ours, i, u, top), "layer {i}: both outcomes");
                let (mut lo, mut hi) = (0, top);
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if accepts(ours, i, u, mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                hi
            };
            assert_eq!(threshold(true), threshold(false), "layer {i}");
        }
    }

    /// The algorithm is `rand_distr::StandardNormal`'s: with the platform's
    /// `exp` and `ln` (the functions `rand_distr` calls here) the draws are bit
    /// for bit its draws on the same generators, 10.2 million draws over
    /// six seeds × streams, and the same words are consumed; the draws
    /// whose first attempt took the wedge and the tail are counted, so both
    /// paths were exercised.
    #[test]
    fn same_draws_as_rand_distr_with_the_platforms_exp_and_ln() {
        use rand_distr::Distribution as _;
        let (mut wedge, mut tail, mut total) = (0u64, 0u64, 0u64);
        for (seed, stream) in SEEDS {
            let mut theirs = generator(seed, stream);
            let mut ours = theirs.clone();
            for n in 0..DRAWS_PER_SEED {
                let mut peek = ours.clone();
                match part(peek.next_u64()) {
                    Part::Box => {}
                    Part::Wedge => wedge += 1,
                    Part::Tail => tail += 1,
                }
                let a: f64 = rand_distr::StandardNormal.sample(&mut theirs);
                let b = ziggurat_platform(&mut ours);
                assert_eq!(b.to_bits(), a.to_bits(), "seed {seed}, stream {stream}, draw {n}: {b:e} against {a:e}");
            }
            assert_eq!(ours.next_u64(), theirs.next_u64(), "seed {seed}: the same words consumed");
            total += DRAWS_PER_SEED;
        }
        println!("{total} draws: first attempt in the wedge {wedge}, in the tail {tail}");
        // Expected: wedge ~1.2 % (~1.2e5), tail (1 − r/x₀)/256 = 2.56e-4 (~2,600).
        assert!(wedge > 50_000, "{wedge} wedge draws");
        assert!(tail > 1_000, "{tail} tail draws");
    }

    /// Seeds and streams of the draw-for-draw comparisons.
    const SEEDS: [(u64, u64); 6] = [(0, 0), (1, 16), (42, 20), (7, 101), (2026, 3), (u64::MAX, 1 << 40)];
    /// Draws per seed of the draw-for-draw comparisons.
    const DRAWS_PER_SEED: u64 = 1_700_000;

    /// What `libm` in place of the platform's `exp` and `ln` moves, on the
    /// draws of [`same_draws_as_rand_distr_with_the_platforms_exp_and_ln`]:
    /// no box draw (~98.8 %, no `exp` or `ln`); a tail draw by a few units
    /// in the last place where `ln` rounds differently; a wedge draw only
    /// if `exp`'s last bit flips the acceptance test, which would also
    /// shift the words that follow (checked: the same words consumed). The
    /// counts are printed.
    #[test]
    fn what_libm_moves() {
        let (mut moved_tail, mut moved_wedge, mut max_ulps, mut tail) = (0u64, 0u64, 0i64, 0u64);
        for (seed, stream) in SEEDS {
            let mut platform = generator(seed, stream);
            let mut ours = platform.clone();
            for n in 0..DRAWS_PER_SEED {
                let first = part(ours.clone().next_u64());
                tail += u64::from(first == Part::Tail);
                let a = ziggurat_platform(&mut platform);
                let b = standard_normal(&mut ours);
                if a.to_bits() != b.to_bits() {
                    let d = ulps(a, b);
                    assert!(first != Part::Box, "seed {seed}, draw {n}: a box draw moved");
                    assert!(d.abs() <= 8, "seed {seed}, draw {n}: {b:e} against {a:e}");
                    max_ulps = max_ulps.max(d.abs());
                    match first {
                        Part::Tail => moved_tail += 1,
                        _ => moved_wedge += 1,
                    }
                }
            }
            assert_eq!(ours.next_u64(), platform.next_u64(), "seed {seed}: the same words consumed");
        }
        println!(
            "libm against the platform's exp/ln: {moved_tail} of {tail} tail draws and {moved_wedge} wedge draws moved, \
             at most {max_ulps} ulp"
        );
        // Log-normal exp(0.1 z) (a Monte Carlo inertia factor): exp on
        // every draw, the same z.
        let (mut rng, n) = (generator(9, 100), 1_000_000);
        let mut moved = 0;
        for _ in 0..n {
            let a = 0.1 * standard_normal(&mut rng);
            let d = ulps(platform_exp(a), math::exp(a));
            assert!(d.abs() <= 1, "exp({a:e}): {d} ulp");
            moved += u32::from(d != 0);
        }
        println!("log-normal(0, 0.1): {moved} of {n} draws moved by one ulp");
    }

    /// `libm`'s `exp` and `ln` against the platform's on the arguments the
    /// ziggurat meets: `exp(−x²/2)` for `x ∈ [0, x₀]` (the wedge) and
    /// `ln U` for `rand`'s `Open01` uniforms (the tail), ten million each:
    /// never more than one unit in the last place apart (both are
    /// faithfully rounded); the share that differs is printed.
    #[test]
    fn libm_and_the_platform_within_one_ulp_on_the_ziggurat_arguments() {
        let mut rng = generator(5, 77);
        let (mut exp_differ, mut ln_differ) = (0u32, 0u32);
        let n = 10_000_000;
        for _ in 0..n {
            let bits = rng.next_u64();
            let x = attempt(bits).2.abs() * (ZIG_X[0] / ZIG_X[bits as usize & 0xff]);
            let a = -x * x / 2.0;
            let d = ulps(platform_exp(a), math::exp(a));
            assert!(d.abs() <= 1, "exp({a:e}): {d} ulp");
            exp_differ += u32::from(d != 0);
            let u = open01(&mut rng);
            let d = ulps(platform_ln(u), math::ln(u));
            assert!(d.abs() <= 1, "ln({u:e}): {d} ulp");
            ln_differ += u32::from(d != 0);
        }
        println!("of {n} arguments each, libm and the platform differ in exp at {exp_differ}, in ln at {ln_differ}");
    }

    /// `Q(a) = P(Z > a)` by Simpson's rule on `[a, a + 12]` (the rest is
    /// below 1e-40), 20,000 panels: a reference independent of the tables.
    fn upper_tail(a: f64) -> f64 {
        let n = 20_000;
        let h = 12.0 / n as f64;
        let g = |t: f64| math::exp(-t * t / 2.0);
        let mut s = g(a) + g(a + 12.0);
        for k in 1..n {
            s += if k % 2 == 1 { 4.0 } else { 2.0 } * g(a + k as f64 * h);
        }
        s * h / 3.0 / math::sqrt(2.0 * core::f64::consts::PI)
    }

    /// Moments and tails of four million draws, on every platform: mean 0,
    /// variance 1, `P(|Z| > 3)` and `P(|Z| > r)` (the tail sampler's part)
    /// within 5 standard errors, and the two signs equally likely beyond r.
    #[test]
    fn draws_are_standard_normal() {
        let n = 4_000_000;
        let mut rng = generator(314, 9);
        let (mut sum, mut sum2, mut beyond3, mut beyond_r, mut beyond_r_neg) = (0.0, 0.0, 0u64, 0u64, 0u64);
        for _ in 0..n {
            let z = standard_normal(&mut rng);
            sum += z;
            sum2 += z * z;
            beyond3 += u64::from(z.abs() > 3.0);
            beyond_r += u64::from(z.abs() > ZIG_R);
            beyond_r_neg += u64::from(z < -ZIG_R);
        }
        let nf = n as f64;
        let mean = sum / nf;
        let var = sum2 / nf - mean * mean;
        assert!(mean.abs() < 5.0 / nf.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 5.0 * (2.0 / nf).sqrt(), "variance {var}");
        for (count, a) in [(beyond3, 3.0), (beyond_r, ZIG_R)] {
            let p = 2.0 * upper_tail(a);
            let got = count as f64 / nf;
            assert!((got - p).abs() < 5.0 * (p / nf).sqrt(), "P(|Z| > {a}) = {got}, expected {p}");
        }
        let half = beyond_r as f64 / 2.0;
        assert!((beyond_r_neg as f64 - half).abs() < 5.0 * half.sqrt() / 2.0 + 1.0, "{beyond_r_neg} of {beyond_r}");
    }

    /// `Normal` is `μ + σ z` and `LogNormal` `exp(μ + σ z)` with the `z`
    /// of [`standard_normal`] on the same generator, one `z` per draw.
    #[test]
    fn normal_and_log_normal_follow_their_definitions() {
        let (mean, std) = (-2.5, 0.3);
        let normal = Normal::new(mean, std).unwrap();
        let log_normal = LogNormal::new(mean, std).unwrap();
        assert_eq!((normal.mean(), normal.std_dev()), (mean, std));
        let (mut a, mut b, mut c) = (generator(3, 4), generator(3, 4), generator(3, 4));
        let mut below_median = 0;
        let n = 200_000;
        for _ in 0..n {
            let z = standard_normal(&mut a);
            assert_eq!(normal.sample(&mut b).to_bits(), (mean + std * z).to_bits());
            let v = log_normal.sample(&mut c);
            assert_eq!(v.to_bits(), math::exp(mean + std * z).to_bits());
            assert!(v > 0.0);
            below_median += u32::from(v < math::exp(mean));
        }
        // The median of exp(N(μ, σ²)) is e^μ.
        let half = f64::from(n) / 2.0;
        assert!((f64::from(below_median) - half).abs() < 5.0 * half.sqrt(), "{below_median} of {n}");
        // A zero deviation gives the mean itself.
        assert_eq!(Normal::new(1.5, 0.0).unwrap().sample(&mut a), 1.5);
        assert_eq!(LogNormal::new(0.0, 0.0).unwrap().sample(&mut a), 1.0);
    }

    /// `rand_distr::Normal` is `μ + σ z` and `rand_distr::LogNormal`
    /// `exp(μ + σ z)` with its standard normal `z` and the platform's
    /// `exp`: the formulas of [`Normal`] and [`LogNormal`], one `z` per
    /// draw.
    #[test]
    fn rand_distr_normal_and_log_normal_are_the_same_formulas() {
        use rand_distr::Distribution as _;
        let theirs_n = rand_distr::Normal::<f64>::new(0.7, 1.9).unwrap();
        let theirs_l = rand_distr::LogNormal::<f64>::new(-0.2, 0.45).unwrap();
        let (mut a, mut b) = (generator(8, 100), generator(8, 100));
        for n in 0..200_000 {
            let normal = 0.7 + 1.9 * ziggurat_platform(&mut a);
            assert_eq!(normal.to_bits(), theirs_n.sample(&mut b).to_bits(), "normal {n}");
            let log_normal = platform_exp(-0.2 + 0.45 * ziggurat_platform(&mut a));
            assert_eq!(log_normal.to_bits(), theirs_l.sample(&mut b).to_bits(), "log-normal {n}");
        }
    }

    /// Non-finite means and negative or non-finite deviations are
    /// refused with an error naming the parameter.
    #[test]
    fn bad_parameters_are_errors() {
        assert!(matches!(Normal::new(f64::NAN, 1.0), Err(GaussError::Mean(m)) if m.is_nan()));
        assert_eq!(Normal::new(f64::INFINITY, 1.0), Err(GaussError::Mean(f64::INFINITY)));
        assert_eq!(Normal::new(0.0, -0.1), Err(GaussError::StdDev(-0.1)));
        assert_eq!(LogNormal::new(0.0, f64::INFINITY), Err(GaussError::StdDev(f64::INFINITY)));
        assert!(matches!(LogNormal::new(0.0, f64::NAN), Err(GaussError::StdDev(s)) if s.is_nan()));
        assert_eq!(LogNormal::new(f64::NEG_INFINITY, 1.0), Err(GaussError::Mean(f64::NEG_INFINITY)));
        let message = Normal::new(0.0, -2.0).unwrap_err().to_string();
        assert!(message.contains("standard deviation") && message.contains("-2"), "{message}");
    }
}
