// A level's points of one sample are consecutive (camera rays in sample
// order, the recursion's rays packed in point order), so a film adds a
// sample's whole run of points from the run's first invocation, in point
// order, and no two invocations touch one sample: the sums are the
// CPU's, bit for bit. Each film declares the level's `points`.

// Whether invocation `index` is the first of its sample's run.
fn starts_run(index: u32) -> bool {
    if index >= params.item_count {
        return false;
    }
    return index == 0u || points[index - 1u].sample != points[index].sample;
}
