/* wide8.cl: the 8-wide layout (Wide8Node, collapsed from the binary tree by
 * src/bvh/wide.rs; src/bvh/wide8.rs): the vector type of its 8 slots, for the traversal
 * of cl/wide.cl, which follows this file in its program. */

#ifndef LAYOUT_WIDE8
#error "wide8.cl is one layout's traversal: its program is built with -D LAYOUT_WIDE8 (src/device/program.rs)"
#endif

#define WIDE_NODE Wide8Node
#define WIDE_F float8
#define WIDE_LOAD vload8
#define WIDE_STORE vstore8
