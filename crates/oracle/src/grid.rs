//! Index arithmetic of regular grids (ours; the voxel grids of section 6.6.2 and the far
//! field's cells of section 6.6.3): linear indices with x fastest.

/// The 6-neighbours of node (or cell) `c` of a grid of `[nx, ny, nz]` nodes that are in the
/// grid, in the order -x, +x, -y, +y, -z, +z.
pub(crate) fn neighbours6(c: usize, [nx, ny, nz]: [usize; 3]) -> impl Iterator<Item = usize> {
    let (x, y, z) = (c % nx, (c / nx) % ny, c / (nx * ny));
    let layer = nx * ny;
    [
        (x > 0).then(|| c - 1),
        (x + 1 < nx).then(|| c + 1),
        (y > 0).then(|| c - nx),
        (y + 1 < ny).then(|| c + nx),
        (z > 0).then(|| c - layer),
        (z + 1 < nz).then(|| c + layer),
    ]
    .into_iter()
    .flatten()
}

#[cfg(test)]
mod tests {
    use super::neighbours6;

    #[test]
    fn neighbours_stay_in_the_grid() {
        let d = [3, 4, 2];
        // A corner has 3, the middle of an edge of the 3 x 4 x 2 grid more.
        assert_eq!(neighbours6(0, d).collect::<Vec<_>>(), vec![1, 3, 12]);
        let c = 1 + 3 * 2 + 12; // (1, 2, 1)
        assert_eq!(
            neighbours6(c, d).collect::<Vec<_>>(),
            vec![c - 1, c + 1, c - 3, c + 3, c - 12]
        );
    }
}
