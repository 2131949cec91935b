//! The iterations' hot passes compiled twice: for the baseline x86-64 (two lanes of
//! f64) and for AVX2 (four), chosen at run time where the CPU has it. The two give
//! the same numbers (no fused multiply-add is allowed, so every operation rounds as
//! before); the wider one takes half the instructions of each pass's arithmetic.

/// Whether this CPU runs the AVX2 versions.
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Defines the method `$name(&self, $wide: bool, …)`, which runs `$body` compiled for
/// AVX2 when `$wide` (which only [`available`] may set) and as written otherwise,
/// with the two copies `$plain` and `$avx2`. The body's closures (the passes given to
/// rayon) inherit the copy's target features; what it calls is compiled once, so
/// the per-entry helpers it calls are `#[inline(always)]`.
macro_rules! twice {
    (
        $(#[$doc:meta])*
        $vis:vis fn $name:ident / $plain:ident / $avx2:ident
            (&$self:ident, $wide:ident: bool $(, $arg:ident: $ty:ty)* $(,)?) $(-> $ret:ty)?
            $body:block
    ) => {
        $(#[$doc])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name(&$self, $wide: bool $(, $arg: $ty)*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            if $wide {
                // SAFETY: `$wide` is set only where `wide::available()` found AVX2.
                #[allow(unsafe_code)]
                return unsafe { $self.$avx2($wide $(, $arg)*) };
            }
            $self.$plain($wide $(, $arg)*)
        }

        #[allow(clippy::too_many_arguments)]
        fn $plain(&$self, $wide: bool $(, $arg: $ty)*) $(-> $ret)? $body

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        fn $avx2(&$self, $wide: bool $(, $arg: $ty)*) $(-> $ret)? $body
    };
}

pub(crate) use twice;
