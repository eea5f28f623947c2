/*
 * Expression evaluation for the CSG language: a stack machine over the postfix
 * expressions of parser.c (so evaluation never recurses), the values it produces,
 * the built-in functions, and the special variables in scope.
 * Semantics follow OpenSCAD where the subset overlaps: numbers are doubles; + - * / % ^
 * on numbers are IEEE operations (% is fmod, ^ is pow; division by zero gives inf or
 * nan, which the modules reject where a finite value is needed); vector + vector and
 * vector - vector are element-wise on numeric vectors of equal length; vector * number,
 * number * vector and vector / number scale; vector * vector is the dot product;
 * sin/cos/tan/asin/acos/atan/atan2 work in degrees with OpenSCAD's exact values (see
 * degree_trig.c); min/max take numbers or one vector. Where OpenSCAD would return undef
 * with a warning (an operator on mismatched types, a function with bad arguments),
 * meshcsg stops with an error naming the line and column instead.
 * Vectors live in a value heap that the caller truncates after each statement; a
 * vector result that sits at the top of the heap and was made by this expression is
 * updated in place, and the heap is capped in proportion to the text's size, so that
 * hostile text cannot make evaluation allocate more than a constant factor of itself.
 */
#include "base/numparse.h"
#include "base/degree_trig.h"
#include "scad/scad.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

const char *scad_string(const scad_program *prog, const scad_value *v)
{
    /* An empty pool has no array at all; never offset a NULL pointer. */
    return v->count ? (const char *)prog->strings.data + v->start : "";
}

const char *scad_type_name(scad_type type)
{
    switch (type) {
    case VAL_UNDEF: return "undef";
    case VAL_BOOL: return "a boolean";
    case VAL_NUMBER: return "a number";
    case VAL_STRING: return "a string";
    case VAL_VECTOR: return "a vector";
    }
    return "?";
}

mcsg_status scad_eval_init(scad_eval *ev, const scad_program *prog, mcsg_error *err)
{
    uint64_t limit = 2 * (uint64_t)prog->size + (1u << 20);
    memset(ev, 0, sizeof *ev);
    ev->prog = prog;
    ev->ctx = prog->ctx;
    ev->heap_limit = limit < UINT32_MAX / 2 ? (uint32_t)limit : UINT32_MAX / 2;
    ev->current = mci_malloc_array(ev->ctx, prog->var_count, sizeof *ev->current);
    if (!ev->current)
        return mci_fail_nomem(err, "evaluating CSG text");
    for (uint32_t i = 0; i < prog->var_count; i++)
        ev->current[i] = SCAD_NONE;
    return MCSG_OK;
}

void scad_eval_free(scad_eval *ev)
{
    if (!ev->ctx)
        return;
    mci_free(ev->ctx, ev->heap);
    mci_free(ev->ctx, ev->stack);
    mci_free(ev->ctx, ev->bindings);
    mci_free(ev->ctx, ev->current);
    memset(ev, 0, sizeof *ev);
}

/* Make room for `extra` more elements in a growable array of `elem`-byte items. */
static bool reserve(const mci_ctx *ctx, void **data, uint32_t *cap, uint32_t len,
                    uint32_t extra, size_t elem)
{
    uint64_t need = (uint64_t)len + extra, new_cap = *cap ? *cap : 64;
    void *grown;
    if (need <= *cap)
        return true;
    while (new_cap < need)
        new_cap *= 2;
    if (new_cap > UINT32_MAX)
        return false;
    grown = mci_realloc_array(ctx, *data, (size_t)new_cap, elem);
    if (!grown)
        return false;
    *data = grown;
    *cap = (uint32_t)new_cap;
    return true;
}

mcsg_status scad_bind(scad_eval *ev, uint32_t var, const scad_value *value, bool active,
                      mcsg_error *err)
{
    void *data = ev->bindings;
    scad_binding *b;
    if (!reserve(ev->ctx, &data, &ev->binding_cap, ev->binding_len, 1, sizeof *b))
        return mci_fail_nomem(err, "evaluating CSG text");
    ev->bindings = data;
    b = &ev->bindings[ev->binding_len];
    b->var = var;
    b->prev = SCAD_NONE;
    b->value = *value;
    b->active = false;
    ev->binding_len++;
    if (active)
        scad_activate_bindings(ev, ev->binding_len - 1);
    return MCSG_OK;
}

void scad_activate_bindings(scad_eval *ev, uint32_t from)
{
    for (uint32_t i = from; i < ev->binding_len; i++) {
        scad_binding *b = &ev->bindings[i];
        if (b->active)
            continue;
        b->prev = ev->current[b->var];
        ev->current[b->var] = i;
        b->active = true;
    }
}

void scad_unbind_to(scad_eval *ev, uint32_t binding_len)
{
    while (ev->binding_len > binding_len) {
        const scad_binding *b = &ev->bindings[--ev->binding_len];
        if (b->active)
            ev->current[b->var] = b->prev;
    }
}

scad_value scad_lookup(const scad_eval *ev, uint32_t var)
{
    scad_value undef;
    if (ev->current[var] != SCAD_NONE)
        return ev->bindings[ev->current[var]].value;
    memset(&undef, 0, sizeof undef);
    return undef;
}

static mcsg_status expr_fail(const scad_eval *ev, const scad_expr *e, mcsg_error *err,
                             const char *what, const char *detail)
{
    return scad_fail_at(ev->prog->name, e->line, e->col, err, MCSG_ERR_PARSE, "%s%s", what,
                        detail);
}

/* Reserve `count` heap elements for a new vector; *start receives their index. */
static mcsg_status heap_alloc(scad_eval *ev, const scad_expr *e, uint32_t count,
                              uint32_t *start, mcsg_error *err)
{
    void *data = ev->heap;
    if ((uint64_t)ev->heap_len + count > ev->heap_limit)
        return scad_fail_at(ev->prog->name, e->line, e->col, err, MCSG_ERR_LIMIT,
                            "expression values exceed %u elements", ev->heap_limit);
    if (!reserve(ev->ctx, &data, &ev->heap_cap, ev->heap_len, count, sizeof(scad_value)))
        return mci_fail_nomem(err, "evaluating CSG text");
    ev->heap = data;
    *start = ev->heap_len;
    ev->heap_len += count;
    return MCSG_OK;
}

static mcsg_status push(scad_eval *ev, const scad_value *v, mcsg_error *err)
{
    void *data = ev->stack;
    if (!reserve(ev->ctx, &data, &ev->stack_cap, ev->stack_len, 1, sizeof *v))
        return mci_fail_nomem(err, "evaluating CSG text");
    ev->stack = data;
    ev->stack[ev->stack_len++] = *v;
    return MCSG_OK;
}

static scad_value number_value(double x)
{
    scad_value v;
    memset(&v, 0, sizeof v);
    v.type = VAL_NUMBER;
    v.number = x;
    return v;
}

static bool is_numeric_vector(const scad_eval *ev, const scad_value *v)
{
    if (v->type != VAL_VECTOR)
        return false;
    for (uint32_t i = 0; i < v->count; i++) {
        if (ev->heap[v->start + i].type != VAL_NUMBER)
            return false;
    }
    return true;
}

static double number_op(scad_expr_op op, double a, double b)
{
    switch (op) {
    case EX_ADD: return a + b;
    case EX_SUB: return a - b;
    case EX_MUL: return a * b;
    case EX_DIV: return a / b;
    case EX_MOD: return fmod(a, b);
    case EX_POW: return pow(a, b);
    default: return NAN;
    }
}

/* Where an element-wise result of `count` elements goes: over a vector operand that
 * this expression made and that sits at the top of the heap, else new elements. */
static mcsg_status result_slots(scad_eval *ev, const scad_expr *e, const scad_value *a,
                                const scad_value *b, uint32_t temp_base, uint32_t count,
                                uint32_t *start, mcsg_error *err)
{
    const scad_value *operands[2] = {b, a};
    for (int i = 0; i < 2; i++) {
        const scad_value *v = operands[i];
        if (v && v->type == VAL_VECTOR && v->start >= temp_base &&
            v->start + v->count == ev->heap_len && v->count == count) {
            *start = v->start;
            return MCSG_OK;
        }
    }
    return heap_alloc(ev, e, count, start, err);
}

/* a (op) b element by element, b a vector or (when scalar_b) the number *b. */
static mcsg_status elementwise(scad_eval *ev, const scad_expr *e, scad_value *a,
                               const scad_value *b, bool scalar_b, bool scalar_first,
                               uint32_t temp_base, mcsg_error *err)
{
    uint32_t start, count = a->count;
    mcsg_status st = result_slots(ev, e, a, scalar_b ? NULL : b, temp_base, count, &start,
                                  err);
    if (st != MCSG_OK)
        return st;
    for (uint32_t i = 0; i < count; i++) {
        double x = ev->heap[a->start + i].number;
        double y = scalar_b ? b->number : ev->heap[b->start + i].number;
        ev->heap[start + i] = number_value(scalar_first ? number_op(e->op, y, x)
                                                        : number_op(e->op, x, y));
    }
    a->start = start;
    return MCSG_OK;
}

static const char *op_symbol(scad_expr_op op)
{
    static const char *const symbols[] = {"+", "-", "*", "/", "%", "^"};
    return (op >= EX_ADD && op <= EX_POW) ? symbols[op - EX_ADD] : "?";
}

static mcsg_status binary(scad_eval *ev, const scad_expr *e, scad_value *a,
                          const scad_value *b, uint32_t temp_base, mcsg_error *err)
{
    scad_expr_op op = (scad_expr_op)e->op;
    bool va = is_numeric_vector(ev, a), vb = is_numeric_vector(ev, b);
    char detail[160];
    if (a->type == VAL_NUMBER && b->type == VAL_NUMBER) {
        a->number = number_op(op, a->number, b->number);
        return MCSG_OK;
    }
    if (va && vb && a->count == b->count && (op == EX_ADD || op == EX_SUB))
        return elementwise(ev, e, a, b, false, false, temp_base, err);
    if (va && vb && a->count == b->count && op == EX_MUL) {
        double dot = 0;
        for (uint32_t i = 0; i < a->count; i++)
            dot += ev->heap[a->start + i].number * ev->heap[b->start + i].number;
        *a = number_value(dot);
        return MCSG_OK;
    }
    if (va && b->type == VAL_NUMBER && (op == EX_MUL || op == EX_DIV))
        return elementwise(ev, e, a, b, true, false, temp_base, err);
    if (vb && a->type == VAL_NUMBER && op == EX_MUL) {
        scad_value scalar = *a;
        *a = *b;
        return elementwise(ev, e, a, &scalar, true, true, temp_base, err);
    }
    snprintf(detail, sizeof detail, " to %s and %s%s", scad_type_name((scad_type)a->type),
             scad_type_name((scad_type)b->type),
             (va && vb) ? " (vectors of different lengths, or a matrix operation)"
             : (a->type == VAL_VECTOR || b->type == VAL_VECTOR) ? " (only numeric vectors "
                                                                  "are supported)" : "");
    return scad_fail_at(ev->prog->name, e->line, e->col, err, MCSG_ERR_PARSE,
                        "cannot apply `%s`%s", op_symbol(op), detail);
}

static mcsg_status negate(scad_eval *ev, const scad_expr *e, scad_value *a,
                          uint32_t temp_base, mcsg_error *err)
{
    if (a->type == VAL_NUMBER) {
        a->number = -a->number;
        return MCSG_OK;
    }
    if (is_numeric_vector(ev, a)) {
        scad_value minus_one = number_value(-1.0);
        scad_expr mul = *e;
        mul.op = EX_MUL; /* exact: -x == x * -1 */
        return elementwise(ev, &mul, a, &minus_one, true, false, temp_base, err);
    }
    return expr_fail(ev, e, err, "cannot negate ", scad_type_name((scad_type)a->type));
}

static mcsg_status make_vector(scad_eval *ev, const scad_expr *e, mcsg_error *err)
{
    uint32_t start, count = e->a;
    scad_value v;
    mcsg_status st = heap_alloc(ev, e, count, &start, err);
    if (st != MCSG_OK)
        return st;
    ev->stack_len -= count;
    if (count)
        memcpy(ev->heap + start, ev->stack + ev->stack_len, count * sizeof(scad_value));
    memset(&v, 0, sizeof v);
    v.type = VAL_VECTOR;
    v.start = start;
    v.count = count;
    return push(ev, &v, err);
}

static double sign_of(double x) { return x < 0 ? -1.0 : (x > 0 ? 1.0 : 0.0); }

/* Functions of one number. */
static bool unary_function(scad_func f, double x, double *out)
{
    switch (f) {
    case FN_SIN: *out = mci_sin_degrees(x); return true;
    case FN_COS: *out = mci_cos_degrees(x); return true;
    case FN_TAN: *out = mci_tan_degrees(x); return true;
    case FN_ASIN: *out = mci_asin_degrees(x); return true;
    case FN_ACOS: *out = mci_acos_degrees(x); return true;
    case FN_ATAN: *out = mci_atan_degrees(x); return true;
    case FN_SQRT: *out = sqrt(x); return true;
    case FN_ABS: *out = fabs(x); return true;
    case FN_FLOOR: *out = floor(x); return true;
    case FN_CEIL: *out = ceil(x); return true;
    case FN_ROUND: *out = round(x); return true;
    case FN_EXP: *out = exp(x); return true;
    case FN_LN: *out = log(x); return true;
    case FN_LOG: *out = log10(x); return true;
    case FN_SIGN: *out = sign_of(x); return true;
    default: return false;
    }
}

/* min/max over numbers, or over the elements of a single numeric vector. */
static bool extremum(const scad_eval *ev, scad_func f, const scad_value *args, uint32_t argc,
                     double *out)
{
    const scad_value *items = args;
    uint32_t n = argc;
    if (argc == 1 && args[0].type == VAL_VECTOR) {
        if (args[0].count == 0)
            return false;
        items = ev->heap + args[0].start;
        n = args[0].count;
    }
    if (n == 0)
        return false;
    for (uint32_t i = 0; i < n; i++) {
        if (items[i].type != VAL_NUMBER)
            return false;
        if (i == 0 || (f == FN_MIN ? items[i].number < *out : items[i].number > *out))
            *out = items[i].number;
    }
    return true;
}

/* norm() and len(). */
static bool measure(const scad_eval *ev, scad_func f, const scad_value *arg, double *out)
{
    const scad_program *prog = ev->prog;
    double sum = 0;
    if (f == FN_LEN && arg->type == VAL_STRING) {
        uint32_t chars = 0; /* UTF-8 code points, as OpenSCAD counts */
        for (uint32_t i = 0; i < arg->count; i++)
            chars += (prog->strings.data[arg->start + i] & 0xC0) != 0x80;
        *out = chars;
        return true;
    }
    if (f == FN_LEN && arg->type == VAL_VECTOR) {
        *out = arg->count;
        return true;
    }
    if (f != FN_NORM || !is_numeric_vector(ev, arg))
        return false;
    for (uint32_t i = 0; i < arg->count; i++)
        sum += ev->heap[arg->start + i].number * ev->heap[arg->start + i].number;
    *out = sqrt(sum);
    return true;
}

static bool apply_function(const scad_eval *ev, scad_func f, const scad_value *args,
                           uint32_t argc, double *out)
{
    bool numbers = true;
    for (uint32_t i = 0; i < argc; i++)
        numbers &= args[i].type == VAL_NUMBER;
    if (f == FN_MIN || f == FN_MAX)
        return extremum(ev, f, args, argc, out);
    if (f == FN_NORM || f == FN_LEN)
        return argc == 1 && measure(ev, f, &args[0], out);
    if (!numbers)
        return false;
    if (f == FN_ATAN2 || f == FN_POW || (f == FN_LOG && argc == 2)) {
        if (argc != 2)
            return false;
        *out = f == FN_ATAN2 ? mci_atan2_degrees(args[0].number, args[1].number)
             : f == FN_POW   ? pow(args[0].number, args[1].number)
                             : log(args[1].number) / log(args[0].number);
        return true;
    }
    return argc == 1 && unary_function(f, args[0].number, out);
}

static mcsg_status call_function(scad_eval *ev, const scad_expr *e, mcsg_error *err)
{
    static const char *const names[FN_COUNT] = {
        "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "abs", "pow", "min",
        "max", "floor", "ceil", "round", "exp", "ln", "log", "sign", "norm", "len"};
    uint32_t argc = e->a;
    double result;
    scad_value v;
    ev->stack_len -= argc;
    if (argc == 0 || !apply_function(ev, (scad_func)e->func, ev->stack + ev->stack_len, argc,
                                     &result))
        return scad_fail_at(ev->prog->name, e->line, e->col, err, MCSG_ERR_PARSE,
                            "%s(): invalid arguments (%u given; functions take numbers, and "
                            "min, max, norm and len also a vector)", names[e->func], argc);
    v = number_value(result);
    return push(ev, &v, err);
}

static mcsg_status eval_node(scad_eval *ev, const scad_expr *e, uint32_t temp_base,
                             mcsg_error *err)
{
    scad_value v, rhs;
    memset(&v, 0, sizeof v);
    switch ((scad_expr_op)e->op) {
    case EX_NUMBER: v = number_value(e->number); break;
    case EX_STRING: v.type = VAL_STRING; v.start = e->a; v.count = e->b; break;
    case EX_BOOL: v.type = VAL_BOOL; v.number = e->a; break;
    case EX_UNDEF: break;
    case EX_SPECIAL:
        if (ev->current[e->a] == SCAD_NONE)
            scad_warn_at(ev->ctx, ev->prog->name, e->line, e->col, "unknown variable %.*s "
                         "(undef)", (int)ev->prog->vars[e->a].len, ev->prog->vars[e->a].text);
        v = scad_lookup(ev, e->a);
        break;
    case EX_NEG:
        return negate(ev, e, &ev->stack[ev->stack_len - 1], temp_base, err);
    case EX_VECTOR:
        return make_vector(ev, e, err);
    case EX_CALL:
        return call_function(ev, e, err);
    default:
        rhs = ev->stack[--ev->stack_len];
        return binary(ev, e, &ev->stack[ev->stack_len - 1], &rhs, temp_base, err);
    }
    return push(ev, &v, err);
}

mcsg_status scad_eval_expr(scad_eval *ev, uint32_t begin, uint32_t end, scad_value *out,
                           mcsg_error *err)
{
    uint32_t base = ev->stack_len, temp_base = ev->heap_len;
    mcsg_status st = MCSG_OK;
    for (uint32_t i = begin; i < end && st == MCSG_OK; i++)
        st = eval_node(ev, &ev->prog->exprs[i], temp_base, err);
    if (st == MCSG_OK)
        *out = ev->stack[base];
    ev->stack_len = base;
    return st;
}

/* Up to 8 elements of vectors nested up to 3 deep; more is abbreviated. */
static bool format_value(const scad_eval *ev, const scad_value *v, mci_buf *buf, int depth)
{
    char num[MCI_DOUBLE_TEXT_MAX];
    bool ok = true;
    switch ((scad_type)v->type) {
    case VAL_UNDEF: return mci_buf_printf(ev->ctx, buf, "%s", "undef");
    case VAL_BOOL: return mci_buf_printf(ev->ctx, buf, "%s", v->number ? "true" : "false");
    case VAL_NUMBER:
        mci_format_double(num, v->number);
        return mci_buf_printf(ev->ctx, buf, "%s", num);
    case VAL_STRING:
        return mci_buf_printf(ev->ctx, buf, "\"%.*s\"", (int)(v->count > 200 ? 200 : v->count),
                              scad_string(ev->prog, v));
    case VAL_VECTOR:
        if (depth >= 3)
            return mci_buf_printf(ev->ctx, buf, "[...]");
        ok = mci_buf_printf(ev->ctx, buf, "[");
        for (uint32_t i = 0; ok && i < v->count && i < 8; i++) {
            ok = (i == 0 || mci_buf_printf(ev->ctx, buf, ", ")) &&
                 format_value(ev, &ev->heap[v->start + i], buf, depth + 1);
        }
        if (ok && v->count > 8)
            ok = mci_buf_printf(ev->ctx, buf, ", ...");
        return ok && mci_buf_printf(ev->ctx, buf, "]");
    }
    return false;
}

bool scad_format_value(const scad_eval *ev, const scad_value *v, mci_buf *buf)
{
    return format_value(ev, v, buf, 0);
}
