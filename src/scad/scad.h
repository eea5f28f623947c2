/*
 * Internal interface between the modules of the CSG-language reader (the OpenSCAD
 * subset described in docs/csg-language.md):
 *   lexer.c     bytes -> tokens (comments, numbers via mci_parse_double, strings)
 *   parser.c    tokens -> program: statements, arguments and expressions in flat
 *               arrays, built without recursion on statement nesting
 *   expr.c      expression evaluation: a stack machine over postfix expressions,
 *               values (numbers, booleans, strings, vectors) and built-in functions
 *   modules.c   the built-in modules: argument binding, primitives, transforms,
 *               polyhedron, import and surface, producing tree nodes
 *   shapes2d.c  the 2D shapes (circle, square, polygon, text, DXF import) as prisms
 *   geometry.c  modules using their children's geometry (extrusions in extrude.c)
 *   prefetch.c  the files of import() calls, read ahead in parallel
 *   scad.c      the public entry points and the non-recursive walk over statements
 * Offsets and counts are 32-bit: texts of 4 GiB or more are refused up front.
 */
#ifndef MESHCSG_SCAD_SCAD_H
#define MESHCSG_SCAD_SCAD_H

#include "base/core.h"

#define SCAD_NONE UINT32_MAX
/* Deepest expression nesting (parentheses, vectors, unary operators, call arguments). */
#define SCAD_MAX_EXPR_DEPTH 256

/* ---------------------------------------------------------------------------------- */
/* Tokens */

typedef enum scad_tok_kind {
    TK_EOF = 0, TK_IDENT, TK_NUMBER, TK_STRING,
    TK_LPAREN, TK_RPAREN, TK_LBRACKET, TK_RBRACKET, TK_LBRACE, TK_RBRACE,
    TK_COMMA, TK_SEMI, TK_ASSIGN, TK_PLUS, TK_MINUS, TK_STAR, TK_SLASH, TK_PERCENT,
    TK_CARET, TK_BANG, TK_HASH, TK_COLON, TK_QUESTION, TK_DOT, TK_LT, TK_GT, TK_LE,
    TK_GE, TK_EQ, TK_NE, TK_AND, TK_OR, TK_TILDE, TK_AMP, TK_PIPE, TK_LSHIFT, TK_RSHIFT
} scad_tok_kind;

typedef struct scad_token {
    scad_tok_kind kind;
    uint32_t line, col;    /* 1-based; col counts bytes */
    uint32_t start, len;   /* the token's bytes in the text */
    double number;         /* TK_NUMBER */
    uint32_t str_off, str_len; /* TK_STRING: decoded bytes in the string pool */
} scad_token;

typedef struct scad_lexer {
    const mci_ctx *ctx;
    const char *text;
    uint32_t size, pos;
    uint32_t line, line_start; /* column = pos - line_start + 1 */
    const char *name;          /* for messages */
    mci_buf *strings;          /* decoded string literals */
} scad_lexer;

/* Read the next token. Errors (MCSG_ERR_PARSE, MCSG_ERR_NOMEM) name name:line:col. */
mcsg_status scad_lex(scad_lexer *lx, scad_token *tok, mcsg_error *err);
/* A short description of a token for messages: "`foo`", "number", "end of file". */
void scad_describe_token(const scad_lexer *lx, const scad_token *tok, char *buf, size_t size);

/* ---------------------------------------------------------------------------------- */
/* Program */

typedef enum scad_expr_op {
    EX_NUMBER, EX_STRING, EX_BOOL, EX_UNDEF, EX_SPECIAL, EX_NEG, EX_ADD, EX_SUB, EX_MUL,
    EX_DIV, EX_MOD, EX_POW, EX_VECTOR, EX_CALL
} scad_expr_op;

typedef enum scad_func {
    FN_SIN, FN_COS, FN_TAN, FN_ASIN, FN_ACOS, FN_ATAN, FN_ATAN2, FN_SQRT, FN_ABS, FN_POW,
    FN_MIN, FN_MAX, FN_FLOOR, FN_CEIL, FN_ROUND, FN_EXP, FN_LN, FN_LOG, FN_SIGN, FN_NORM,
    FN_LEN, FN_COUNT
} scad_func;

/* One node of a postfix expression: operands come before their operator, so an
 * expression is a contiguous range evaluated left to right with a value stack. */
typedef struct scad_expr {
    uint8_t op;   /* scad_expr_op */
    uint8_t func; /* EX_CALL: scad_func */
    uint32_t line, col;
    uint32_t a, b; /* EX_STRING: pool offset, length; EX_VECTOR/EX_CALL: count in a;
                      EX_SPECIAL: variable id in a; EX_BOOL: value in a */
    double number; /* EX_NUMBER */
} scad_expr;

typedef struct scad_arg {
    uint32_t name_start, name_len; /* name_len 0: positional */
    uint32_t var;                  /* a $name: its special variable id, else SCAD_NONE */
    uint32_t expr_begin, expr_end; /* [begin, end) in the expression array */
    uint32_t line, col;
} scad_arg;

typedef enum scad_module {
    MOD_UNION, MOD_DIFFERENCE, MOD_INTERSECTION, MOD_GROUP, MOD_RENDER, MOD_COLOR,
    MOD_TRANSLATE, MOD_ROTATE, MOD_SCALE, MOD_MIRROR, MOD_MULTMATRIX, MOD_CUBE, MOD_SPHERE,
    MOD_CYLINDER, MOD_POLYHEDRON, MOD_IMPORT, MOD_SURFACE, MOD_CIRCLE, MOD_SQUARE, MOD_POLYGON, MOD_TEXT,
    MOD_LINEAR_EXTRUDE, MOD_ROTATE_EXTRUDE, MOD_HULL, MOD_MINKOWSKI, MOD_OFFSET,
    MOD_PROJECTION, MOD_RESIZE, MOD_COUNT
} scad_module;

/* Modules that work on their children's evaluated geometry. */
static inline bool scad_is_geometry_module(scad_module m)
{
    return m >= MOD_LINEAR_EXTRUDE && m <= MOD_RESIZE;
}

enum { ST_ROOT, ST_CALL, ST_ASSIGN };
enum { MODIFIER_DISABLE = 1, MODIFIER_BACKGROUND = 2, MODIFIER_HIGHLIGHT = 4 };

/* A statement. The statements of a scope (a call's children, or the file) form a list
 * through `next`, in source order; assignments are part of that list. */
typedef struct scad_stmt {
    uint8_t kind;      /* ST_* */
    uint8_t module;    /* ST_CALL: scad_module */
    uint8_t modifiers; /* ST_CALL: MODIFIER_* */
    uint32_t line, col;
    uint32_t arg_begin, arg_count;  /* ST_CALL */
    uint32_t var;                   /* ST_ASSIGN: special variable id */
    uint32_t expr_begin, expr_end;  /* ST_ASSIGN */
    uint32_t first_child, last_child, next;
} scad_stmt;

/* Special variables ($fn, ...) are interned: id -> name in the text. The first ones
 * are predefined, with fixed ids. */
enum { VAR_FN, VAR_FA, VAR_FS, VAR_T, VAR_PREVIEW, VAR_PREDEFINED };

typedef struct scad_name {
    const char *text; /* in the program text, not NUL-terminated */
    uint32_t len;
} scad_name;

typedef struct scad_program {
    const mci_ctx *ctx;
    const char *text;
    uint32_t size;
    const char *name;
    scad_stmt *stmts;  /* stmts[0] is the file's root scope */
    uint32_t stmt_count, stmt_cap;
    scad_arg *args;
    uint32_t arg_count, arg_cap;
    scad_expr *exprs;
    uint32_t expr_count, expr_cap;
    mci_buf strings;  /* decoded string literals */
    scad_name *vars;  /* special variable id -> name */
    uint32_t var_count, var_cap;
    uint32_t *var_hash; /* open addressing: id + 1, 0 = empty */
    uint32_t var_hash_cap;
} scad_program;

/* Parse `text` into *prog (which must be zeroed). On failure the program may hold
 * partial results: release it with scad_program_free in every case. */
mcsg_status scad_parse(scad_program *prog, const mci_ctx *ctx, const char *text,
                       uint32_t size, const char *name, mcsg_error *err);
void scad_program_free(scad_program *prog);

/* The module's name ("cube", ...) and the comma-separated list of supported ones. */
const char *scad_module_name(scad_module module);
extern const char scad_supported_modules[];

/* ---------------------------------------------------------------------------------- */
/* Values and expression evaluation */

typedef enum scad_type { VAL_UNDEF, VAL_BOOL, VAL_NUMBER, VAL_STRING, VAL_VECTOR } scad_type;

/* A value. Strings point into the program's string pool, vectors into the evaluator's
 * value heap (elements heap[start .. start+count)). */
typedef struct scad_value {
    uint8_t type;
    uint32_t start, count;
    double number; /* VAL_NUMBER; VAL_BOOL: 0 or 1 */
} scad_value;

typedef struct scad_binding {
    uint32_t var, prev; /* prev: the binding this one shadows, or SCAD_NONE */
    bool active;
    scad_value value;
} scad_binding;

typedef struct scad_eval {
    const scad_program *prog;
    const mci_ctx *ctx;
    scad_value *heap;     /* vector elements */
    uint32_t heap_len, heap_cap, heap_limit;
    scad_value *stack;    /* operands during one expression */
    uint32_t stack_len, stack_cap;
    scad_binding *bindings; /* special variables in scope, innermost last */
    uint32_t binding_len, binding_cap;
    uint32_t *current;    /* var id -> innermost binding, or SCAD_NONE */
} scad_eval;

mcsg_status scad_eval_init(scad_eval *ev, const scad_program *prog, mcsg_error *err);
void scad_eval_free(scad_eval *ev);
/* Evaluate exprs[begin, end) to *out (valid until the heap is truncated below it). */
mcsg_status scad_eval_expr(scad_eval *ev, uint32_t begin, uint32_t end, scad_value *out,
                           mcsg_error *err);
/* Bind a special variable in the innermost scope; scad_unbind_to pops bindings. A
 * binding made with active = false takes effect only at scad_activate_bindings(ev, from),
 * which activates every inactive binding from index `from` on, in order. */
mcsg_status scad_bind(scad_eval *ev, uint32_t var, const scad_value *value, bool active,
                      mcsg_error *err);
void scad_activate_bindings(scad_eval *ev, uint32_t from);
void scad_unbind_to(scad_eval *ev, uint32_t binding_len);
/* The value of a special variable, or undef. */
scad_value scad_lookup(const scad_eval *ev, uint32_t var);
const char *scad_type_name(scad_type type);
/* The bytes of a string value (count of them; "" when empty). */
const char *scad_string(const scad_program *prog, const scad_value *v);
/* Append a printable form of a value ("[1, 2, 3]", "\"a.off\"") to buf. */
bool scad_format_value(const scad_eval *ev, const scad_value *v, mci_buf *buf);

/* ---------------------------------------------------------------------------------- */
/* Module instantiation (modules.c), driven by the walk in scad.c */

/* An affine map (row-major 3x4) with a flag for maps that flatten everything, and where
 * it stands among frames (mesh/tree.h): a transform that turns space opens a frame for
 * its children; `rel` maps into the innermost open frame (equal to m when none is). */
typedef struct scad_transform {
    double m[12];
    double rel[12];
    double frame_rel[12]; /* when opens_frame: the new frame into the enclosing one */
    bool degenerate;
    bool in_frame;        /* some frame is open */
    bool opens_frame;
} scad_transform;

/* Meshes of import() calls read ahead of the walk (prefetch.c). */
typedef struct scad_prefetch {
    struct prefetched *entries; /* sorted by path */
    size_t count;
} scad_prefetch;

typedef struct scad_context {
    scad_eval ev;
    const scad_program *prog;
    const mcsg_options *opts;
    mcsg_tree *tree;
    const char *base_dir; /* NULL: current directory */
    const char *name;     /* for messages and labels */
    scad_prefetch prefetch;
} scad_context;

/* Whether an import() file name ends in .3mf (case-insensitive): such a file gives a
 * leaf per build item, read by import() itself, not prefetched as one mesh. */
bool scad_is_3mf_name(const char *file, uint32_t len);
/* Whether an import() file name ends in .amf: a leaf per object, read by import() itself. */
bool scad_is_amf_name(const char *file, uint32_t len);
/* Whether an import() file name ends in .dxf: a 2D drawing, read by import() itself. */
bool scad_is_dxf_name(const char *file, uint32_t len);
/* Whether an import() file name ends in .svg (case-insensitive): a 2D drawing, read by
 * import() itself. */
bool scad_is_svg_name(const char *file, uint32_t len);

/* Read the files of every import() call with a literal file name, on the options'
 * threads, into sc->prefetch (failed reads are kept as failures, not reported). */
mcsg_status scad_prefetch_imports(scad_context *sc, mcsg_error *err);
/* The mesh read ahead for `path`, if there is one (*found): moved out for its last
 * call, copied for the others; the messages its read logged are logged again. */
mcsg_status scad_prefetch_take(scad_context *sc, const char *path, mcsg_mesh *mesh,
                               bool *found, mcsg_error *err);
void scad_prefetch_free(scad_context *sc);

/* ---------------------------------------------------------------------------------- */
/* Arguments of a call, bound to its module's parameters (modules.c) */

#define SCAD_MAX_PARAMS 14

typedef struct scad_bound_arg {
    scad_value value; /* undef when not given */
    uint32_t line, col;
    bool named;
} scad_bound_arg;

typedef struct scad_call_args {
    const scad_stmt *stmt;
    const char *module;
    scad_bound_arg slot[SCAD_MAX_PARAMS];
} scad_call_args;

/* Evaluate and bind every argument of the call, OpenSCAD's way (modules.c); its
 * $-arguments are bound as special variables (the caller unbinds them). */
mcsg_status scad_bind_arguments(scad_context *sc, const scad_stmt *stmt, scad_call_args *ca,
                                mcsg_error *err);
bool scad_given(const scad_call_args *ca, int slot);
const scad_value *scad_element(const scad_context *sc, const scad_value *v, uint32_t i);
/* "MODULE(): `PARAM` must be EXPECTED, not TYPE" at the argument (or the call). */
mcsg_status scad_wrong_type(const scad_context *sc, const scad_call_args *ca, int slot,
                            const char *expected, mcsg_error *err);
/* A number or a boolean, if given (else *x or *b is left alone). */
mcsg_status scad_arg_number(const scad_context *sc, const scad_call_args *ca, int slot,
                            double *x, mcsg_error *err);
mcsg_status scad_arg_bool(const scad_context *sc, const scad_call_args *ca, int slot, bool *b,
                          mcsg_error *err);
/* A vector of 3 numbers, or of 2 when two_ok (the third is then `z`). */
bool scad_get_vec3(const scad_context *sc, const scad_value *v, bool two_ok, double z,
                   double out[3]);
/* OpenSCAD's lookup_radius: the diameter, halved, if given; else the radius. */
mcsg_status scad_arg_radius(const scad_context *sc, const scad_call_args *ca, int d_slot,
                            int r_slot, double *r, bool *defined, mcsg_error *err);
/* $fn, $fa, $fs in scope, with OpenSCAD's clamping of $fa and $fs. */
mcsg_status scad_get_resolution(scad_context *sc, const scad_call_args *ca,
                                mcsg_resolution *res, mcsg_error *err);
/* Append ", $fn=..." or ", $fa=..., $fs=..." (or PREFIX and a number) to a label. */
bool scad_put_resolution(const mci_ctx *ctx, mci_buf *buf, const mcsg_resolution *res);
bool scad_put_number(const mci_ctx *ctx, mci_buf *buf, const char *prefix, double x);
bool scad_is_identity(const double m[12]);
/* A failure from a library call given the call's position ("F:L:C: MODULE(): ..."). */
mcsg_status scad_at_call(const scad_context *sc, const scad_call_args *ca, mcsg_status st,
                         mcsg_error *err);
/* Add the leaf for `mesh` (taking it) under transform t, labelled "<label> at F:L:C";
 * an empty mesh or a flattening transform gives the empty set instead. */
mcsg_status scad_add_leaf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                          mcsg_mesh *mesh, mci_buf *label, mcsg_node_id *node,
                          mcsg_error *err);
/* Free the mesh and fail for want of memory. */
mcsg_status scad_nomem_label(mcsg_mesh *mesh, const mci_ctx *ctx, mcsg_error *err);

/* ---------------------------------------------------------------------------------- */
/* 2D shapes (shapes2d.c) and the modules that use their children's geometry
 * (geometry.c) */

/* Dimension of a walk result: DIM_NONE for the empty set of no dimension (a group
 * without children). 2D objects are prisms from z = 0 to 1 over their region in the
 * tree being built; only modules that use geometry read them back (region.h). */
typedef enum scad_dim { DIM_NONE = 0, DIM_2D = 2, DIM_3D = 3 } scad_dim;

/* How a DXF drawing is read: layer (NULL: all), origin, scale, and the resolution its
 * arcs are split by. */
typedef struct scad_dxf_view {
    const char *layer;
    double origin[2];
    double scale;
    mcsg_resolution res;
} scad_dxf_view;

/* A DXF drawing's outlines (file_len bytes of `file` for messages, opened at `path`) as
 * a 2D leaf under t, labelled import("file"); read errors name the call's module and
 * place (shapes2d.c). */
mcsg_status scad_add_dxf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                         const char *file, uint32_t file_len, const char *path,
                         const scad_dxf_view *view, mcsg_node_id *node, mcsg_error *err);
/* The file named by argument `slot` (a non-empty string) resolved against the base
 * directory into `path` (NUL-terminated); *file and *file_len the name as written
 * (modules.c). */
mcsg_status scad_file_path(scad_context *sc, const scad_call_args *ca, int slot,
                           const char **file, uint32_t *file_len, struct mci_buf *path,
                           mcsg_error *err);

/* import() of a DXF drawing: its outlines as a 2D leaf (shapes2d.c). */
mcsg_status scad_import_dxf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                            const char *file, uint32_t file_len, const char *path,
                            mcsg_node_id *node, mcsg_error *err);
/* import() of an SVG drawing: each shape's even-odd fill, united, as a 2D leaf
 * (shapes2d.c). */
mcsg_status scad_import_svg(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                            const char *file, uint32_t file_len, const char *path,
                            mcsg_node_id *node, mcsg_error *err);
/* circle, square, polygon: add the prism of the shape, under the 2D part of t. */
mcsg_status scad_make_shape2d(scad_context *sc, const scad_call_args *ca,
                              const scad_transform *t, mcsg_node_id *node, mcsg_error *err);
/* The non-zero fill of outlines that may cross (text(): composite glyphs, glyphs set
 * closer than their width), as outlines that do not: one piece per loop turning the way
 * the largest one does, with the loops inside it, united by the engine (geometry.c). */
struct mci_outlines;
mcsg_status scad_fill_nonzero(scad_context *sc, struct mci_outlines *o,
                              struct mci_outlines *filled, mcsg_error *err);
/* Add the region the outlines fill (even-odd) under the 2D part of t, as a prism leaf
 * labelled "<label> at F:L:C", or the empty set; the outlines' points are transformed in
 * place. */
struct mci_outlines;
mcsg_status scad_add_shape(scad_context *sc, const scad_call_args *ca,
                           const scad_transform *t, struct mci_outlines *o, mci_buf *label,
                           mcsg_node_id *node, mcsg_error *err);

/* A geometry module's arguments, read when its call is entered. */
typedef struct scad_geometry_op {
    uint32_t stmt;
    scad_call_args ca;     /* for messages: its values are not used once read (the
                              children reuse the value heap) */
    mcsg_resolution res;
    double height, twist, scale[2], angle; /* linear_extrude, rotate_extrude */
    int slices;            /* 0: not given */
    bool center;
    double delta;          /* offset */
    int join;              /* offset: SCAD_JOIN_* */
    bool cut;              /* projection */
    double newsize[3];     /* resize */
    bool autosize[3];
    mcsg_tree *outer;      /* the tree the result goes into */
} scad_geometry_op;

enum { SCAD_JOIN_ROUND, SCAD_JOIN_MITER, SCAD_JOIN_SQUARE };

/* Read the arguments of geometry module call `stmt` (special variables bound). */
mcsg_status scad_geometry_begin(scad_context *sc, uint32_t stmt, scad_geometry_op *op,
                                mcsg_error *err);
/* The children are done: `count` nodes of dimension `dim` in sc->tree (the op's own
 * tree). Evaluate them and make the op's result into op->outer under transform t: *out
 * and its dimension. sc->tree is left alone (the caller restores and frees). */
mcsg_status scad_geometry_finish(scad_context *sc, scad_geometry_op *op,
                                 const mcsg_node_id *children, size_t count, scad_dim dim,
                                 const scad_transform *t, mcsg_node_id *out,
                                 scad_dim *out_dim, mcsg_error *err);

/* The deprecated `file` of linear_extrude and rotate_extrude, read before the children:
 * the drawing as the op's first child in its own tree (*given false without one;
 * geometry.c). */
mcsg_status scad_geometry_file(scad_context *sc, scad_geometry_op *op, mcsg_node_id *node,
                               bool *given, mcsg_error *err);

/* What a call with children contributes once its children are done. */
typedef enum scad_role { ROLE_OP, ROLE_GROUP } scad_role;

/* Evaluate the arguments of call `stmt`. For a primitive, polyhedron or import, add
 * its leaf (or an empty union) under `parent` and set *node and *dim; otherwise fill *child
 * with the transform for the children (parent's, composed with the call's own) and
 * *role. Special variables passed as arguments are bound (the caller unbinds them). */
mcsg_status scad_instantiate(scad_context *sc, uint32_t stmt, const scad_transform *parent,
                             scad_transform *child, scad_role *role, mcsg_node_id *node,
                             scad_dim *dim, mcsg_error *err);

/* Fail with "NAME:LINE:COL: message" and the given status. */
mcsg_status scad_fail_at(const char *name, uint32_t line, uint32_t col, mcsg_error *err,
                         mcsg_status status, const char *fmt, ...) MCI_PRINTF(6, 7);
/* Warn through the log with the same prefix. */
void scad_warn_at(const mci_ctx *ctx, const char *name, uint32_t line, uint32_t col,
                  const char *fmt, ...) MCI_PRINTF(5, 6);

#endif
