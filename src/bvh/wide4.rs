//! `wide4`: the binary tree collapsed into 4-wide nodes (128 bytes), traversed by
//! `cl/wide4.cl`.

use bytemuck::{Pod, Zeroable};

super::wide::wide_node!(Wide4Node, 4);
