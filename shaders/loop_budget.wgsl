// Completion check for kernels whose invocations loop long. llvmpipe (Mesa's lavapipe) gives
// each invocation one budget of 65,535 loop iterations shared by all of its loops (gallivm's
// LP_MAX_TGSI_LOOP_ITERATIONS, src/gallium/auxiliary/gallivm/lp_bld_limits.h); once it is
// spent, every loop stops after its current iteration, silently. A loop whose trip count is
// known only at run time (`trips`, from the host, so that no compiler unrolls it), run after
// the work, therefore completes only when the budget held. Kernels then write CUT_SHORT
// instead of their result, and the host splits the work over more invocations
// (src/gpu/loop_budget.rs).

const CUT_SHORT: u32 = 0xffffffffu;

fn loops_completed(trips: u32) -> bool {
    var done = 0u;
    for (var s = 0u; s < trips; s++) {
        done += 1u;
    }
    return done == trips;
}
