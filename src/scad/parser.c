/*
 * Parser for the CSG language: OpenSCAD's grammar (src/core/parser.y) restricted to the
 * subset meshcsg evaluates. Statements are parsed with an explicit stack of open scopes,
 * so nesting depth is limited by memory only; expressions use recursive descent with
 * OpenSCAD's precedence (additive < multiplicative < unary < exponent < call), limited to
 * SCAD_MAX_EXPR_DEPTH levels. Constructs outside the subset that OpenSCAD accepts
 * (comparisons, ternaries, indexing, ranges, list comprehensions, user variables,
 * modules and functions, control flow, use/include, 2D and extrusion modules) are
 * reported as MCSG_ERR_UNSUPPORTED at their line and column, never skipped; text that
 * OpenSCAD itself would reject is MCSG_ERR_PARSE.
 * OpenSCAD's scope rules: the statements inside a call's braces form that call's scope;
 * bare braces at statement level add to the enclosing scope; a call without braces has
 * exactly one child statement (or none, with `;`); modifiers `*`, `%`, `#` (and `!`,
 * which meshcsg rejects) prefix a call.
 */
#include "scad/scad.h"

#include <math.h>
#include <string.h>

#define PI_DOUBLE 3.14159265358979323846

/* Where an expression node comes from; kept small since the expression parser recurses. */
typedef struct source_pos {
    uint32_t line, col;
    scad_tok_kind kind;
} source_pos;

static source_pos pos_of(const scad_token *tok)
{
    source_pos pos;
    pos.line = tok->line;
    pos.col = tok->col;
    pos.kind = tok->kind;
    return pos;
}

typedef struct parser {
    scad_program *prog;
    scad_lexer lx;
    scad_token tok;   /* current token */
    scad_token ahead; /* the one after it, when has_ahead */
    bool has_ahead;
    uint32_t depth;   /* expression nesting */
    mcsg_error *err;
    char found[64];   /* a token described for a message; here rather than on the stack,
                         which the recursive expression parser keeps small */
} parser;

static const char *const module_names[MOD_COUNT] = {
    "union", "difference", "intersection", "group", "render", "color", "translate",
    "rotate", "scale", "mirror", "multmatrix", "cube", "sphere", "cylinder", "polyhedron",
    "import", "surface", "circle", "square", "polygon", "text", "linear_extrude", "rotate_extrude", "hull",
    "minkowski", "offset", "projection", "resize",
};

const char scad_supported_modules[] =
    "union, difference, intersection, group, render, color, translate, rotate, scale, "
    "mirror, multmatrix, cube, sphere, cylinder, polyhedron, import, surface, circle, square, "
    "polygon, text, linear_extrude, rotate_extrude, hull, minkowski, offset, projection, resize, "
    "and assignments to $fn, $fa, $fs";

/* OpenSCAD keywords and built-in modules that meshcsg recognises but does not support. */
static const char *const unsupported_names[] = {
    "module", "function", "use", "include", "if", "else", "for", "intersection_for", "let",
    "each", "assert", "echo", "children", "roof", "fill", "parent_module", "debug", NULL,
};

static const char *const function_names[FN_COUNT] = {
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "abs", "pow", "min",
    "max", "floor", "ceil", "round", "exp", "ln", "log", "sign", "norm", "len",
};

const char *scad_module_name(scad_module module)
{
    return module < MOD_COUNT ? module_names[module] : "?";
}

/* ---------------------------------------------------------------------------------- */
/* Storage */

/* Grow an array to hold count+1 elements; NULL on failure (the old array stays). */
static void *grow(const mci_ctx *ctx, void *data, uint32_t *cap, uint32_t count, size_t elem)
{
    uint32_t new_cap;
    void *grown;
    if (count < *cap)
        return data;
    if (*cap >= UINT32_MAX / 2)
        return NULL;
    new_cap = *cap ? *cap * 2 : 64;
    grown = mci_realloc_array(ctx, data, new_cap, elem);
    if (grown)
        *cap = new_cap;
    return grown;
}

static bool token_is(const parser *p, const scad_token *tok, const char *word)
{
    size_t n = strlen(word);
    return tok->kind == TK_IDENT && tok->len == n &&
           memcmp(p->prog->text + tok->start, word, n) == 0;
}

static int find_name(const parser *p, const scad_token *tok, const char *const *names, int count)
{
    for (int i = 0; count < 0 ? names[i] != NULL : i < count; i++) {
        if (token_is(p, tok, names[i]))
            return i;
    }
    return -1;
}

static uint32_t hash_name(const char *s, uint32_t n)
{
    uint32_t h = 2166136261u; /* FNV-1a */
    for (uint32_t i = 0; i < n; i++)
        h = (h ^ (unsigned char)s[i]) * 16777619u;
    return h;
}

static bool rehash_vars(scad_program *prog, uint32_t cap)
{
    uint32_t *table = mci_calloc_array(prog->ctx, cap, sizeof *table);
    if (!table)
        return false;
    for (uint32_t id = 0; id < prog->var_count; id++) {
        uint32_t h = hash_name(prog->vars[id].text, prog->vars[id].len) & (cap - 1);
        while (table[h])
            h = (h + 1) & (cap - 1);
        table[h] = id + 1;
    }
    mci_free(prog->ctx, prog->var_hash);
    prog->var_hash = table;
    prog->var_hash_cap = cap;
    return true;
}

/* The id of special variable `name` (n bytes), adding it if new. */
static mcsg_status intern_var(scad_program *prog, const char *name, uint32_t n, uint32_t *id,
                              mcsg_error *err)
{
    uint32_t h;
    scad_name *vars;
    if (prog->var_hash_cap == 0 || prog->var_count * 2 >= prog->var_hash_cap) {
        if (prog->var_hash_cap >= UINT32_MAX / 4 ||
            !rehash_vars(prog, prog->var_hash_cap ? prog->var_hash_cap * 2 : 64))
            return mci_fail_nomem(err, "reading CSG text");
    }
    h = hash_name(name, n) & (prog->var_hash_cap - 1);
    for (; prog->var_hash[h]; h = (h + 1) & (prog->var_hash_cap - 1)) {
        const scad_name *known = &prog->vars[prog->var_hash[h] - 1];
        if (known->len == n && memcmp(known->text, name, n) == 0) {
            *id = prog->var_hash[h] - 1;
            return MCSG_OK;
        }
    }
    vars = grow(prog->ctx, prog->vars, &prog->var_cap, prog->var_count, sizeof *vars);
    if (!vars)
        return mci_fail_nomem(err, "reading CSG text");
    prog->vars = vars;
    vars[prog->var_count].text = name;
    vars[prog->var_count].len = n;
    prog->var_hash[h] = prog->var_count + 1;
    *id = prog->var_count++;
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Tokens and messages */

static mcsg_status advance(parser *p)
{
    if (p->has_ahead) {
        p->tok = p->ahead;
        p->has_ahead = false;
        return MCSG_OK;
    }
    return scad_lex(&p->lx, &p->tok, p->err);
}

/* The token after the current one. */
static mcsg_status look_ahead(parser *p, const scad_token **out)
{
    if (!p->has_ahead) {
        mcsg_status st = scad_lex(&p->lx, &p->ahead, p->err);
        if (st != MCSG_OK)
            return st;
        p->has_ahead = true;
    }
    *out = &p->ahead;
    return MCSG_OK;
}

static mcsg_status fail_at_token(parser *p, mcsg_status status, const char *what)
{
    scad_describe_token(&p->lx, &p->tok, p->found, sizeof p->found);
    return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, status,
                        "%s, found %s", what, p->found);
}

static mcsg_status expect(parser *p, scad_tok_kind kind, const char *what)
{
    if (p->tok.kind != kind)
        return fail_at_token(p, MCSG_ERR_PARSE, what);
    return advance(p);
}

static mcsg_status unsupported_here(parser *p, const char *what)
{
    return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, MCSG_ERR_UNSUPPORTED,
                        "%s", what);
}

/* ---------------------------------------------------------------------------------- */
/* Expressions */

static mcsg_status emit(parser *p, scad_expr_op op, source_pos at, uint32_t *index)
{
    scad_program *prog = p->prog;
    scad_expr *exprs = grow(prog->ctx, prog->exprs, &prog->expr_cap, prog->expr_count,
                            sizeof *exprs);
    if (!exprs)
        return mci_fail_nomem(p->err, "reading CSG text");
    prog->exprs = exprs;
    memset(&exprs[prog->expr_count], 0, sizeof exprs[0]);
    exprs[prog->expr_count].op = (uint8_t)op;
    exprs[prog->expr_count].line = at.line;
    exprs[prog->expr_count].col = at.col;
    if (index)
        *index = prog->expr_count;
    prog->expr_count++;
    return MCSG_OK;
}

static mcsg_status parse_expr(parser *p);
static mcsg_status parse_unary(parser *p);

/* The operators of OpenSCAD's grammar that the subset leaves out. */
static mcsg_status reject_operator(parser *p)
{
    static const scad_tok_kind rejected[] = {TK_QUESTION, TK_LT, TK_GT, TK_LE, TK_GE, TK_EQ,
                                             TK_NE, TK_AND, TK_OR, TK_PIPE, TK_AMP,
                                             TK_LSHIFT, TK_RSHIFT};
    for (size_t i = 0; i < sizeof rejected / sizeof rejected[0]; i++) {
        if (p->tok.kind == rejected[i]) {
            scad_describe_token(&p->lx, &p->tok, p->found, sizeof p->found);
            return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err,
                                MCSG_ERR_UNSUPPORTED, "operator %s is not supported by "
                                "meshcsg (expressions may use + - * / %% ^, parentheses, "
                                "vectors and built-in functions)", p->found);
        }
    }
    return MCSG_OK;
}

/* Comma-separated expressions up to `close`, with an optional trailing comma. */
static mcsg_status parse_list(parser *p, scad_tok_kind close, const char *what, uint32_t *count)
{
    mcsg_status st = MCSG_OK;
    *count = 0;
    while (st == MCSG_OK && p->tok.kind != close) {
        st = parse_expr(p);
        if (st == MCSG_OK && p->tok.kind == TK_COLON && close == TK_RBRACKET)
            return unsupported_here(p, "ranges ([a:b]) are not supported by meshcsg");
        if (st == MCSG_OK && ++*count == UINT32_MAX)
            return unsupported_here(p, "too many elements");
        if (st == MCSG_OK && p->tok.kind != close)
            st = expect(p, TK_COMMA, what);
    }
    return st == MCSG_OK ? advance(p) : st;
}

static mcsg_status parse_vector(parser *p)
{
    source_pos open = pos_of(&p->tok);
    uint32_t count, index;
    mcsg_status st = advance(p);
    if (st == MCSG_OK && (token_is(p, &p->tok, "for") || token_is(p, &p->tok, "each") ||
                          token_is(p, &p->tok, "let") || token_is(p, &p->tok, "if")))
        return unsupported_here(p, "list comprehensions are not supported by meshcsg");
    if (st == MCSG_OK)
        st = parse_list(p, TK_RBRACKET, "expected `,` or `]` in a vector", &count);
    if (st == MCSG_OK)
        st = emit(p, EX_VECTOR, open, &index);
    if (st == MCSG_OK)
        p->prog->exprs[index].a = count;
    return st;
}

static mcsg_status parse_call(parser *p, scad_func func)
{
    source_pos name = pos_of(&p->tok);
    const scad_token *next;
    uint32_t count, index;
    mcsg_status st = advance(p);
    if (st != MCSG_OK)
        return st;
    if (p->tok.kind != TK_LPAREN)
        return fail_at_token(p, MCSG_ERR_PARSE, "expected `(` after a function name");
    st = advance(p);
    if (st == MCSG_OK && p->tok.kind == TK_IDENT && (st = look_ahead(p, &next)) == MCSG_OK &&
        next->kind == TK_ASSIGN)
        return unsupported_here(p, "named arguments to functions are not supported");
    if (st == MCSG_OK)
        st = parse_list(p, TK_RPAREN, "expected `,` or `)` in a function call", &count);
    if (st == MCSG_OK)
        st = emit(p, EX_CALL, name, &index);
    if (st == MCSG_OK) {
        p->prog->exprs[index].a = count;
        p->prog->exprs[index].func = (uint8_t)func;
    }
    return st;
}

static mcsg_status parse_identifier(parser *p)
{
    static const char *const keywords[] = {"let", "assert", "echo", "function", "each", "for",
                                           "if", "else", NULL};
    const scad_token *next;
    uint32_t index;
    int func = find_name(p, &p->tok, function_names, FN_COUNT);
    mcsg_status st;
    if (token_is(p, &p->tok, "true") || token_is(p, &p->tok, "false")) {
        st = emit(p, EX_BOOL, pos_of(&p->tok), &index);
        if (st == MCSG_OK)
            p->prog->exprs[index].a = token_is(p, &p->tok, "true");
    } else if (token_is(p, &p->tok, "undef")) {
        st = emit(p, EX_UNDEF, pos_of(&p->tok), NULL);
    } else if (token_is(p, &p->tok, "PI")) {
        st = emit(p, EX_NUMBER, pos_of(&p->tok), &index);
        if (st == MCSG_OK)
            p->prog->exprs[index].number = PI_DOUBLE;
    } else if (p->prog->text[p->tok.start] == '$') {
        uint32_t var;
        st = intern_var(p->prog, p->prog->text + p->tok.start, p->tok.len, &var, p->err);
        if (st == MCSG_OK)
            st = emit(p, EX_SPECIAL, pos_of(&p->tok), &index);
        if (st == MCSG_OK)
            p->prog->exprs[index].a = var;
    } else if (func >= 0) {
        return parse_call(p, (scad_func)func);
    } else if (find_name(p, &p->tok, keywords, -1) >= 0) {
        return fail_at_token(p, MCSG_ERR_UNSUPPORTED, "this construct is not supported in "
                             "meshcsg expressions");
    } else if ((st = look_ahead(p, &next)) != MCSG_OK) {
        return st;
    } else if (next->kind == TK_LPAREN) {
        return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err,
                            MCSG_ERR_UNSUPPORTED, "function `%.*s` is not supported by meshcsg "
                            "(no user-defined functions; built-in: sin, cos, tan, asin, acos, "
                            "atan, atan2, sqrt, abs, pow, min, max, floor, ceil, round, exp, ln, "
                            "log, sign, norm, len)", (int)p->tok.len,
                            p->prog->text + p->tok.start);
    } else {
        return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err,
                            MCSG_ERR_UNSUPPORTED, "variable `%.*s` is not supported by meshcsg "
                            "(no user variables; only special variables such as $fn, and PI)",
                            (int)p->tok.len, p->prog->text + p->tok.start);
    }
    return st == MCSG_OK ? advance(p) : st;
}

static mcsg_status parse_primary(parser *p)
{
    uint32_t index;
    mcsg_status st;
    switch (p->tok.kind) {
    case TK_NUMBER:
        st = emit(p, EX_NUMBER, pos_of(&p->tok), &index);
        if (st == MCSG_OK)
            p->prog->exprs[index].number = p->tok.number;
        return st == MCSG_OK ? advance(p) : st;
    case TK_STRING:
        st = emit(p, EX_STRING, pos_of(&p->tok), &index);
        if (st == MCSG_OK) {
            p->prog->exprs[index].a = p->tok.str_off;
            p->prog->exprs[index].b = p->tok.str_len;
        }
        return st == MCSG_OK ? advance(p) : st;
    case TK_IDENT:
        return parse_identifier(p);
    case TK_LPAREN:
        st = advance(p);
        if (st == MCSG_OK)
            st = parse_expr(p);
        return st == MCSG_OK ? expect(p, TK_RPAREN, "expected `)`") : st;
    case TK_LBRACKET:
        return parse_vector(p);
    case TK_LBRACE:
        return unsupported_here(p, "objects ({...} in an expression) are not supported by "
                                   "meshcsg");
    default:
        return fail_at_token(p, MCSG_ERR_PARSE, "expected an expression");
    }
}

static mcsg_status parse_exponent(parser *p)
{
    source_pos op;
    mcsg_status st = parse_primary(p);
    if (st == MCSG_OK && p->tok.kind == TK_LBRACKET)
        return unsupported_here(p, "indexing (v[i]) is not supported by meshcsg");
    if (st == MCSG_OK && p->tok.kind == TK_DOT)
        return unsupported_here(p, "member access (v.x) is not supported by meshcsg");
    if (st != MCSG_OK || p->tok.kind != TK_CARET)
        return st;
    op = pos_of(&p->tok);
    st = advance(p);
    if (st == MCSG_OK)
        st = parse_unary(p); /* right-associative, as in OpenSCAD */
    return st == MCSG_OK ? emit(p, EX_POW, op, NULL) : st;
}

/* Unary operators. Every level of expression nesting (parentheses, vectors, call
 * arguments, unary and exponent chains) passes through here once, so the depth is
 * counted here only. */
static mcsg_status parse_unary(parser *p)
{
    source_pos op = pos_of(&p->tok);
    uint32_t operand = p->prog->expr_count;
    mcsg_status st;
    if (op.kind == TK_BANG || op.kind == TK_TILDE)
        return unsupported_here(p, "logical and bitwise operators are not supported by "
                                   "meshcsg");
    if (p->depth >= SCAD_MAX_EXPR_DEPTH)
        return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, MCSG_ERR_LIMIT,
                            "expression nested more than %d levels deep", SCAD_MAX_EXPR_DEPTH);
    p->depth++;
    if (op.kind != TK_PLUS && op.kind != TK_MINUS) {
        st = parse_exponent(p);
    } else {
        st = advance(p);
        if (st == MCSG_OK)
            st = parse_unary(p);
    }
    p->depth--;
    if (st != MCSG_OK || op.kind != TK_MINUS)
        return st;
    if (p->prog->expr_count == operand + 1 && p->prog->exprs[operand].op == EX_NUMBER) {
        /* Fold -literal into a literal, as OpenSCAD's parser does. */
        p->prog->exprs[operand].number = -p->prog->exprs[operand].number;
        return MCSG_OK;
    }
    return emit(p, EX_NEG, op, NULL);
}

static mcsg_status parse_multiplicative(parser *p)
{
    mcsg_status st = parse_unary(p);
    while (st == MCSG_OK &&
           (p->tok.kind == TK_STAR || p->tok.kind == TK_SLASH || p->tok.kind == TK_PERCENT)) {
        source_pos op = pos_of(&p->tok);
        st = advance(p);
        if (st == MCSG_OK)
            st = parse_unary(p);
        if (st == MCSG_OK)
            st = emit(p, op.kind == TK_STAR ? EX_MUL : op.kind == TK_SLASH ? EX_DIV : EX_MOD,
                      op, NULL);
    }
    return st;
}

/* expr: additive, followed by none of the operators the subset leaves out. */
static mcsg_status parse_expr(parser *p)
{
    mcsg_status st = parse_multiplicative(p);
    while (st == MCSG_OK && (p->tok.kind == TK_PLUS || p->tok.kind == TK_MINUS)) {
        source_pos op = pos_of(&p->tok);
        st = advance(p);
        if (st == MCSG_OK)
            st = parse_multiplicative(p);
        if (st == MCSG_OK)
            st = emit(p, op.kind == TK_PLUS ? EX_ADD : EX_SUB, op, NULL);
    }
    return st == MCSG_OK ? reject_operator(p) : st;
}

/* ---------------------------------------------------------------------------------- */
/* Statements */

/* A new statement, appended to the scope of `parent`. */
static mcsg_status new_stmt(parser *p, uint8_t kind, const scad_token *at, uint32_t parent,
                            uint32_t *index)
{
    scad_program *prog = p->prog;
    scad_stmt *stmts = grow(prog->ctx, prog->stmts, &prog->stmt_cap, prog->stmt_count,
                            sizeof *stmts);
    scad_stmt *s;
    if (!stmts)
        return mci_fail_nomem(p->err, "reading CSG text");
    prog->stmts = stmts;
    s = &stmts[prog->stmt_count];
    memset(s, 0, sizeof *s);
    s->kind = kind;
    s->line = at ? at->line : 1;
    s->col = at ? at->col : 1;
    s->first_child = s->last_child = s->next = SCAD_NONE;
    if (parent != SCAD_NONE) {
        scad_stmt *up = &stmts[parent];
        if (up->last_child == SCAD_NONE)
            up->first_child = prog->stmt_count;
        else
            stmts[up->last_child].next = prog->stmt_count;
        up->last_child = prog->stmt_count;
    }
    *index = prog->stmt_count++;
    return MCSG_OK;
}

static mcsg_status parse_argument(parser *p)
{
    scad_program *prog = p->prog;
    const scad_token *next;
    scad_arg *args = grow(prog->ctx, prog->args, &prog->arg_cap, prog->arg_count, sizeof *args);
    scad_arg arg;
    mcsg_status st = MCSG_OK;
    if (!args)
        return mci_fail_nomem(p->err, "reading CSG text");
    prog->args = args;
    memset(&arg, 0, sizeof arg);
    arg.line = p->tok.line;
    arg.col = p->tok.col;
    arg.var = SCAD_NONE;
    if (p->tok.kind == TK_IDENT && (st = look_ahead(p, &next)) == MCSG_OK &&
        next->kind == TK_ASSIGN) {
        arg.name_start = p->tok.start;
        arg.name_len = p->tok.len;
        if (prog->text[p->tok.start] == '$')
            st = intern_var(prog, prog->text + p->tok.start, p->tok.len, &arg.var, p->err);
        if (st == MCSG_OK)
            st = advance(p);
        if (st == MCSG_OK)
            st = advance(p);
    }
    arg.expr_begin = prog->expr_count;
    if (st == MCSG_OK)
        st = parse_expr(p);
    arg.expr_end = prog->expr_count;
    if (st == MCSG_OK)
        prog->args[prog->arg_count++] = arg;
    return st;
}

/* ( [argument {, argument}] [,] ) */
static mcsg_status parse_arguments(parser *p, scad_stmt *call)
{
    mcsg_status st = expect(p, TK_LPAREN, "expected `(` after the module name");
    call->arg_begin = p->prog->arg_count;
    while (st == MCSG_OK && p->tok.kind != TK_RPAREN) {
        st = parse_argument(p);
        if (st == MCSG_OK && p->tok.kind != TK_RPAREN)
            st = expect(p, TK_COMMA, "expected `,` or `)` after an argument");
    }
    call->arg_count = p->prog->arg_count - call->arg_begin;
    return st == MCSG_OK ? advance(p) : st;
}

/* The module a call names: supported, known but unsupported, or unknown. */
static mcsg_status resolve_module(parser *p, scad_module *module)
{
    int found = find_name(p, &p->tok, module_names, MOD_COUNT);
    if (found >= 0) {
        *module = (scad_module)found;
        return MCSG_OK;
    }
    if (find_name(p, &p->tok, unsupported_names, -1) >= 0)
        return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err,
                            MCSG_ERR_UNSUPPORTED, "`%.*s` is not supported by meshcsg "
                            "(supported: %s)", (int)p->tok.len, p->prog->text + p->tok.start,
                            scad_supported_modules);
    if (p->tok.kind != TK_IDENT)
        return fail_at_token(p, MCSG_ERR_PARSE, "expected a statement");
    return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, MCSG_ERR_PARSE,
                        "unknown module `%.*s` (supported: %s)", (int)p->tok.len,
                        p->prog->text + p->tok.start, scad_supported_modules);
}

/* [modifiers] name ( arguments ) -- the child statement is parsed by the caller. */
static mcsg_status parse_module_call(parser *p, uint32_t parent, uint32_t *index)
{
    scad_token start = p->tok;
    uint8_t modifiers = 0;
    scad_module module = MOD_UNION;
    mcsg_status st = MCSG_OK;
    while (st == MCSG_OK && (p->tok.kind == TK_STAR || p->tok.kind == TK_PERCENT ||
                             p->tok.kind == TK_HASH || p->tok.kind == TK_BANG)) {
        if (p->tok.kind == TK_BANG)
            return unsupported_here(p, "the root modifier `!` is not supported by meshcsg "
                                       "(remove it to use the whole file)");
        modifiers |= p->tok.kind == TK_STAR      ? MODIFIER_DISABLE
                     : p->tok.kind == TK_PERCENT ? MODIFIER_BACKGROUND
                                                 : MODIFIER_HIGHLIGHT;
        st = advance(p);
    }
    if (st == MCSG_OK)
        st = resolve_module(p, &module);
    if (st == MCSG_OK)
        st = new_stmt(p, ST_CALL, &start, parent, index);
    if (st != MCSG_OK)
        return st;
    p->prog->stmts[*index].module = (uint8_t)module;
    p->prog->stmts[*index].modifiers = modifiers;
    st = advance(p);
    return st == MCSG_OK ? parse_arguments(p, &p->prog->stmts[*index]) : st;
}

/* $name = expr ; */
static mcsg_status parse_assignment(parser *p, uint32_t parent)
{
    scad_token name = p->tok;
    uint32_t index, var;
    mcsg_status st;
    if (p->prog->text[name.start] != '$')
        return scad_fail_at(p->prog->name, name.line, name.col, p->err, MCSG_ERR_UNSUPPORTED,
                            "assignment to `%.*s` is not supported by meshcsg (no user "
                            "variables; only special variables such as $fn, $fa, $fs)",
                            (int)name.len, p->prog->text + name.start);
    st = intern_var(p->prog, p->prog->text + name.start, name.len, &var, p->err);
    if (st == MCSG_OK)
        st = new_stmt(p, ST_ASSIGN, &name, parent, &index);
    if (st == MCSG_OK)
        st = advance(p); /* name */
    if (st == MCSG_OK)
        st = advance(p); /* = */
    if (st != MCSG_OK)
        return st;
    p->prog->stmts[index].var = var;
    p->prog->stmts[index].expr_begin = p->prog->expr_count;
    st = parse_expr(p);
    p->prog->stmts[index].expr_end = p->prog->expr_count;
    return st == MCSG_OK ? expect(p, TK_SEMI, "expected `;` after an assignment") : st;
}

/* An open construct on the statement stack. */
typedef enum frame_mode {
    FRAME_FILE,   /* the file's scope, closed by end of file */
    FRAME_BLOCK,  /* a call's { ... } scope */
    FRAME_BRACE,  /* bare { ... } inside a scope: same scope */
    FRAME_SINGLE  /* a call waiting for its one child statement */
} frame_mode;

typedef struct parse_frame {
    uint32_t stmt; /* the call (or root) whose scope receives new statements */
    uint32_t line, col;
    uint8_t mode;
} parse_frame;

typedef struct frame_stack {
    parse_frame *items;
    uint32_t len, cap;
} frame_stack;

static mcsg_status push_frame(parser *p, frame_stack *fs, uint32_t stmt, frame_mode mode)
{
    parse_frame *items = grow(p->prog->ctx, fs->items, &fs->cap, fs->len, sizeof *items);
    if (!items)
        return mci_fail_nomem(p->err, "reading CSG text");
    fs->items = items;
    items[fs->len].stmt = stmt;
    items[fs->len].line = p->tok.line;
    items[fs->len].col = p->tok.col;
    items[fs->len].mode = (uint8_t)mode;
    fs->len++;
    return MCSG_OK;
}

/* A statement just ended: every call waiting for exactly one child is now complete. */
static void complete_statement(frame_stack *fs)
{
    while (fs->items[fs->len - 1].mode == FRAME_SINGLE)
        fs->len--;
}

static mcsg_status unexpected_end(parser *p, const parse_frame *top)
{
    if (top->mode == FRAME_SINGLE)
        return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, MCSG_ERR_PARSE,
                            "unexpected end of file: expected a statement or `;` after `%s(...)` "
                            "at line %u", scad_module_name(p->prog->stmts[top->stmt].module),
                            top->line);
    return scad_fail_at(p->prog->name, p->tok.line, p->tok.col, p->err, MCSG_ERR_PARSE,
                        "unexpected end of file: expected `}` to close the `{` at line %u, "
                        "column %u", top->line, top->col);
}

static mcsg_status close_brace(parser *p, frame_stack *fs)
{
    parse_frame *top = &fs->items[fs->len - 1];
    if (top->mode == FRAME_FILE || top->mode == FRAME_SINGLE)
        return fail_at_token(p, MCSG_ERR_PARSE, top->mode == FRAME_FILE
                             ? "unmatched `}`" : "expected a statement or `;`");
    fs->len--;
    if (top->mode == FRAME_BLOCK)
        complete_statement(fs); /* the block was its call's child statement */
    return advance(p);
}

/* One step of the statement loop, at the current token. */
static mcsg_status parse_step(parser *p, frame_stack *fs)
{
    parse_frame *top = &fs->items[fs->len - 1];
    const scad_token *next;
    uint32_t index;
    mcsg_status st;
    switch (p->tok.kind) {
    case TK_RBRACE:
        return close_brace(p, fs);
    case TK_SEMI:
        complete_statement(fs);
        return advance(p);
    case TK_LBRACE:
        if (top->mode == FRAME_SINGLE) {
            top->mode = FRAME_BLOCK;
            top->line = p->tok.line;
            top->col = p->tok.col;
            return advance(p);
        }
        st = push_frame(p, fs, top->stmt, FRAME_BRACE);
        return st == MCSG_OK ? advance(p) : st;
    default:
        break;
    }
    if (p->tok.kind == TK_IDENT && find_name(p, &p->tok, unsupported_names, -1) < 0) {
        st = look_ahead(p, &next);
        if (st == MCSG_OK && next->kind == TK_ASSIGN) {
            if (top->mode == FRAME_SINGLE)
                return fail_at_token(p, MCSG_ERR_PARSE, "expected a module call as the child "
                                     "statement (an assignment needs braces around it)");
            return parse_assignment(p, top->stmt);
        }
        if (st != MCSG_OK)
            return st;
    }
    st = parse_module_call(p, top->stmt, &index);
    return st == MCSG_OK ? push_frame(p, fs, index, FRAME_SINGLE) : st;
}

static mcsg_status parse_statements(parser *p)
{
    frame_stack fs = {NULL, 0, 0};
    uint32_t root;
    mcsg_status st = new_stmt(p, ST_ROOT, NULL, SCAD_NONE, &root);
    if (st == MCSG_OK)
        st = advance(p);
    if (st == MCSG_OK)
        st = push_frame(p, &fs, root, FRAME_FILE);
    while (st == MCSG_OK) {
        if (p->tok.kind == TK_EOF) {
            if (fs.len > 1)
                st = unexpected_end(p, &fs.items[fs.len - 1]);
            break;
        }
        st = parse_step(p, &fs);
    }
    mci_free(p->prog->ctx, fs.items);
    return st;
}

mcsg_status scad_parse(scad_program *prog, const mci_ctx *ctx, const char *text,
                       uint32_t size, const char *name, mcsg_error *err)
{
    static const char *const predefined[VAR_PREDEFINED] = {"$fn", "$fa", "$fs", "$t",
                                                           "$preview"};
    parser p;
    mcsg_status st = MCSG_OK;
    memset(prog, 0, sizeof *prog);
    prog->ctx = ctx;
    prog->text = text;
    prog->size = size;
    prog->name = name;
    for (uint32_t i = 0, id; i < VAR_PREDEFINED && st == MCSG_OK; i++)
        st = intern_var(prog, predefined[i], (uint32_t)strlen(predefined[i]), &id, err);
    if (st != MCSG_OK)
        return st;
    memset(&p, 0, sizeof p);
    p.prog = prog;
    p.err = err;
    p.lx.ctx = ctx;
    p.lx.text = text;
    p.lx.size = size;
    p.lx.line = 1;
    p.lx.name = name;
    p.lx.strings = &prog->strings;
    return parse_statements(&p);
}

void scad_program_free(scad_program *prog)
{
    const mci_ctx *ctx = prog->ctx;
    if (!ctx)
        return;
    mci_free(ctx, prog->stmts);
    mci_free(ctx, prog->args);
    mci_free(ctx, prog->exprs);
    mci_buf_free(ctx, &prog->strings);
    mci_free(ctx, prog->vars);
    mci_free(ctx, prog->var_hash);
    memset(prog, 0, sizeof *prog);
}
