//! `wide8`: the binary tree collapsed into 8-wide nodes (256 bytes), traversed by
//! `cl/wide8.cl`.

use bytemuck::{Pod, Zeroable};

super::wide::wide_node!(Wide8Node, 8);
