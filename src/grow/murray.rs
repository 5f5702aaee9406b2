//! Vein widths by Murray's law, r_parent^n = Σ r_child^n (Murray 1926; Peele §3.1.3), computed
//! once on a growth tree from the tips (radius `tip`) to the roots.

/// Radius of every node of the tree given by `parent` (None for roots). Children must come after
/// their parents in the order, as growth produces them.
pub fn radii(parent: &[Option<u32>], exponent: f64, tip: f64) -> Vec<f64> {
    let n = parent.len();
    let mut sum = vec![0.0f64; n]; // Σ r_child^n collected from children
    let mut radius = vec![0.0f64; n];
    for v in (0..n).rev() {
        radius[v] = if sum[v] > 0.0 {
            sum[v].powf(1.0 / exponent)
        } else {
            tip
        };
        if let Some(p) = parent[v] {
            debug_assert!((p as usize) < v, "children come after parents");
            sum[p as usize] += radius[v].powf(exponent);
        }
    }
    radius
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn murray_holds_at_a_fork_and_along_a_chain() {
        // 0 -> 1 -> {2, 3}; 3 -> 4
        let parent = [None, Some(0), Some(1), Some(1), Some(3)];
        let r = radii(&parent, 3.0, 0.5);
        assert_eq!(r[2], 0.5);
        assert_eq!(r[4], 0.5);
        assert_eq!(r[3], 0.5, "a chain keeps its width");
        assert!((r[1].powi(3) - 2.0 * 0.5f64.powi(3)).abs() < 1e-12);
        assert_eq!(r[0], r[1]);
    }
}
