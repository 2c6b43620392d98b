/* nodes.cl: the node struct of every BVH layout, each mirroring the #[repr(C)] Rust struct
 * of its name in src/bvh/ (tests/layout.rs pins sizes and field offsets through probe.cl).
 * A BVH program reads the one of its layout file; the probe reads them all. */

/* A 32-byte binary node, depth-first order. An inner node holds its children's indices; a
 * leaf holds its first triangle and, in `right_or_count`, LEAF_FLAG | triangle count. */
typedef struct {
    float min[3]; uint left_or_first;
    float max[3]; uint right_or_count;
} Bin32Node;

/* The Aila-Laine layout: a 64-byte node holding both children's boxes. refs: left child,
 * right child, left count, right count; a child with count 0 is an inner node (its index),
 * with count > 0 a leaf of that many triangles from its index. */
typedef struct {
    float left_xy[4];   /* min.x, max.x, min.y, max.y */
    float right_xy[4];
    float z[4];         /* left min.z, max.z, right min.z, max.z */
    uint refs[4];
} Bin64Node;

/* Wide nodes: the children's boxes plane by plane, then their references (count 0: inner
 * node; count > 0: leaf; EMPTY_SLOT: unused). */
typedef struct {
    float min_x[4], max_x[4], min_y[4], max_y[4], min_z[4], max_z[4];
    uint child[4], count[4];
} Wide4Node;
typedef struct {
    float min_x[8], max_x[8], min_y[8], max_y[8], min_z[8], max_z[8];
    uint child[8], count[8];
} Wide8Node;

/* A compressed 8-wide node (Ylitie et al. 2017): slot k's box on axis a is
 * origin[a] + q * 2^(exponent[a] - 127) for q = lo_a[k] and hi_a[k]. Inner children are
 * contiguous from child_base in slot order (inner_mask bit k: slot k is inner); leaf
 * children's triangles are contiguous from triangle_base. meta[k]: 0 empty; inner
 * 0x38 | k; a leaf of n triangles (2^n - 1) << 5 | offset from triangle_base. */
typedef struct {
    float origin[3];
    uchar exponent[3]; uchar inner_mask;
    uint child_base;
    uint triangle_base;
    uchar meta[8];
    uchar lo_x[8], lo_y[8], lo_z[8], hi_x[8], hi_y[8], hi_z[8];
} CwbvhNode;
