/* wide4.cl: the 4-wide layout (Wide4Node, collapsed from the binary tree by
 * src/bvh/wide.rs; src/bvh/wide4.rs): the vector type of its 4 slots, for the traversal
 * of cl/wide.cl, which follows this file in its program. */

#ifndef LAYOUT_WIDE4
#error "wide4.cl is one layout's traversal: its program is built with -D LAYOUT_WIDE4 (src/device/program.rs)"
#endif

#define WIDE_NODE Wide4Node
#define WIDE_F float4
#define WIDE_LOAD vload4
#define WIDE_STORE vstore4
