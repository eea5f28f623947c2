/*
 * Tokenizer for the CSG language, following OpenSCAD's lexer.l where it matters:
 *  - comments: // to the end of the line and non-nesting block comments; an unterminated
 *    block comment is an error at its opening;
 *  - numbers: digits with an optional fraction and exponent (1, 1., .5, 1e-3) parsed
 *    exactly by mci_parse_double (correctly rounded, whatever the C locale), and
 *    hexadecimal integers 0x1F; a number glued to letters ("3d", "1e") is an error;
 *  - strings: "..." may span lines; escapes \n \t \r \\ \" \xHH (HH <= 7F; \x00 becomes
 *    \x01 as in OpenSCAD), \uHHHH and \UHHHHHH (encoded as UTF-8); another backslash is
 *    kept as it is; an unterminated string is an error at its opening quote;
 *  - identifiers: a letter or underscore, then letters, digits, underscores, with an
 *    optional leading $ for special variables;
 *  - a UTF-8 byte-order mark at the start is skipped; any other byte outside strings and
 *    comments that starts no token (including NUL) is an error.
 * Lines are counted at '\n'; columns count bytes from 1.
 */
#include "base/numparse.h"
#include "scad/scad.h"

#include <stdio.h>
#include <string.h>

static bool is_digit(int c) { return c >= '0' && c <= '9'; }
static bool is_alpha(int c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
static bool is_ident_char(int c) { return is_alpha(c) || is_digit(c); }

static int hex_value(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static int peek_at(const scad_lexer *lx, uint32_t offset)
{
    uint32_t p = lx->pos + offset;
    return (offset < lx->size && p < lx->size) ? (unsigned char)lx->text[p] : -1;
}

static void advance(scad_lexer *lx)
{
    if (lx->text[lx->pos] == '\n') {
        if (lx->line < UINT32_MAX)
            lx->line++;
        lx->line_start = lx->pos + 1;
    }
    lx->pos++;
}

static uint32_t column(const scad_lexer *lx) { return lx->pos - lx->line_start + 1; }

static mcsg_status lex_fail(const scad_lexer *lx, uint32_t line, uint32_t col,
                            mcsg_error *err, const char *what)
{
    return scad_fail_at(lx->name, line, col, err, MCSG_ERR_PARSE, "%s", what);
}

/* Skip blanks and comments. */
static mcsg_status skip_space(scad_lexer *lx, mcsg_error *err)
{
    for (;;) {
        int c = peek_at(lx, 0);
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') {
            advance(lx);
        } else if (c == '/' && peek_at(lx, 1) == '/') {
            while (peek_at(lx, 0) >= 0 && peek_at(lx, 0) != '\n')
                advance(lx);
        } else if (c == '/' && peek_at(lx, 1) == '*') {
            uint32_t line = lx->line, col = column(lx);
            advance(lx);
            advance(lx);
            while (!(peek_at(lx, 0) == '*' && peek_at(lx, 1) == '/')) {
                if (peek_at(lx, 0) < 0)
                    return lex_fail(lx, line, col, err, "unterminated comment: `/*` without "
                                    "a closing `*/`");
                advance(lx);
            }
            advance(lx);
            advance(lx);
        } else {
            return MCSG_OK;
        }
    }
}

static mcsg_status lex_hex(scad_lexer *lx, scad_token *tok)
{
    double value = 0;
    lx->pos += 2;
    while (hex_value(peek_at(lx, 0)) >= 0) {
        value = value * 16 + hex_value(peek_at(lx, 0));
        lx->pos++;
    }
    tok->number = value;
    return MCSG_OK;
}

/* {D}+{E}? | {D}*\.{D}+{E}? | {D}+\.{D}*{E}?  or  0x{H}+ */
static mcsg_status lex_number(scad_lexer *lx, scad_token *tok, mcsg_error *err)
{
    const char *next;
    uint32_t start = lx->pos;
    if (peek_at(lx, 0) == '0' && (peek_at(lx, 1) == 'x' || peek_at(lx, 1) == 'X') &&
        hex_value(peek_at(lx, 2)) >= 0) {
        lex_hex(lx, tok);
    } else {
        while (is_digit(peek_at(lx, 0)))
            lx->pos++;
        if (peek_at(lx, 0) == '.')
            lx->pos++;
        while (is_digit(peek_at(lx, 0)))
            lx->pos++;
        if ((peek_at(lx, 0) == 'e' || peek_at(lx, 0) == 'E') &&
            (is_digit(peek_at(lx, 1)) ||
             ((peek_at(lx, 1) == '+' || peek_at(lx, 1) == '-') && is_digit(peek_at(lx, 2))))) {
            lx->pos += 2;
            while (is_digit(peek_at(lx, 0)))
                lx->pos++;
        }
        if (!mci_parse_double(lx->text + start, lx->text + lx->pos, &tok->number, &next) ||
            next != lx->text + lx->pos)
            return lex_fail(lx, tok->line, tok->col, err, "invalid number");
    }
    if (is_ident_char(peek_at(lx, 0)) || peek_at(lx, 0) == '.')
        return scad_fail_at(lx->name, tok->line, tok->col, err, MCSG_ERR_PARSE,
                            "invalid number `%.*s%c`", (int)(lx->pos - start),
                            lx->text + start, peek_at(lx, 0));
    tok->kind = TK_NUMBER;
    return MCSG_OK;
}

/* Append code point cp as UTF-8 (invalid ones as U+FFFD). */
static bool put_utf8(scad_lexer *lx, unsigned long cp)
{
    unsigned char b[4];
    size_t n;
    if (cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
        cp = 0xFFFD;
    if (cp < 0x80) {
        b[0] = (unsigned char)cp;
        n = 1;
    } else if (cp < 0x800) {
        b[0] = (unsigned char)(0xC0 | (cp >> 6));
        b[1] = (unsigned char)(0x80 | (cp & 0x3F));
        n = 2;
    } else if (cp < 0x10000) {
        b[0] = (unsigned char)(0xE0 | (cp >> 12));
        b[1] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        b[2] = (unsigned char)(0x80 | (cp & 0x3F));
        n = 3;
    } else {
        b[0] = (unsigned char)(0xF0 | (cp >> 18));
        b[1] = (unsigned char)(0x80 | ((cp >> 12) & 0x3F));
        b[2] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        b[3] = (unsigned char)(0x80 | (cp & 0x3F));
        n = 4;
    }
    return mci_buf_append(lx->ctx, lx->strings, b, n);
}

/* Number of hex digits at offset 1.. (after the escape letter), up to `max`. */
static int hex_digits(const scad_lexer *lx, int max)
{
    int n = 0;
    while (n < max && hex_value(peek_at(lx, (uint32_t)(2 + n))) >= 0)
        n++;
    return n;
}

static unsigned long hex_number(const scad_lexer *lx, int digits)
{
    unsigned long v = 0;
    for (int i = 0; i < digits; i++)
        v = v * 16 + (unsigned long)hex_value(peek_at(lx, (uint32_t)(2 + i)));
    return v;
}

/* One escape sequence at a backslash; consumes it and appends its bytes. */
static bool lex_escape(scad_lexer *lx)
{
    static const char plain_from[] = "ntr\\\"", plain_to[] = "\n\t\r\\\"";
    int c = peek_at(lx, 1);
    const char *plain = c > 0 ? strchr(plain_from, c) : NULL;
    if (plain) {
        lx->pos += 2;
        return mci_buf_append(lx->ctx, lx->strings, plain_to + (plain - plain_from), 1);
    }
    if (c == 'x' && peek_at(lx, 2) >= '0' && peek_at(lx, 2) <= '7' && hex_digits(lx, 2) == 2) {
        unsigned char byte = (unsigned char)hex_number(lx, 2);
        lx->pos += 4;
        byte = byte ? byte : 1;
        return mci_buf_append(lx->ctx, lx->strings, &byte, 1);
    }
    if ((c == 'u' && hex_digits(lx, 4) == 4) || (c == 'U' && hex_digits(lx, 6) == 6)) {
        int digits = c == 'u' ? 4 : 6;
        unsigned long cp = hex_number(lx, digits);
        lx->pos += 2 + (uint32_t)digits;
        return put_utf8(lx, cp);
    }
    lx->pos++; /* not an escape: keep the backslash */
    return mci_buf_append(lx->ctx, lx->strings, "\\", 1);
}

static mcsg_status lex_string(scad_lexer *lx, scad_token *tok, mcsg_error *err)
{
    tok->str_off = (uint32_t)lx->strings->len;
    advance(lx); /* opening quote */
    for (;;) {
        int c = peek_at(lx, 0);
        bool ok;
        if (c < 0)
            return lex_fail(lx, tok->line, tok->col, err, "unterminated string: `\"` without "
                            "a closing `\"`");
        if (c == '"')
            break;
        if (c == '\\') {
            ok = lex_escape(lx);
        } else {
            char byte = (char)c;
            ok = mci_buf_append(lx->ctx, lx->strings, &byte, 1);
            advance(lx);
        }
        if (!ok)
            return mci_fail_nomem(err, "reading a string literal");
    }
    advance(lx); /* closing quote */
    tok->kind = TK_STRING;
    tok->str_len = (uint32_t)(lx->strings->len - tok->str_off);
    return MCSG_OK;
}

/* Punctuation: two-character operators first. */
static bool lex_punct(scad_lexer *lx, scad_token *tok)
{
    static const struct { char text[3]; scad_tok_kind kind; } table[] = {
        {"<=", TK_LE}, {">=", TK_GE}, {"==", TK_EQ}, {"!=", TK_NE}, {"&&", TK_AND},
        {"||", TK_OR}, {"<<", TK_LSHIFT}, {">>", TK_RSHIFT}, {"(", TK_LPAREN},
        {")", TK_RPAREN}, {"[", TK_LBRACKET}, {"]", TK_RBRACKET}, {"{", TK_LBRACE},
        {"}", TK_RBRACE}, {",", TK_COMMA}, {";", TK_SEMI}, {"=", TK_ASSIGN}, {"+", TK_PLUS},
        {"-", TK_MINUS}, {"*", TK_STAR}, {"/", TK_SLASH}, {"%", TK_PERCENT}, {"^", TK_CARET},
        {"!", TK_BANG}, {"#", TK_HASH}, {":", TK_COLON}, {"?", TK_QUESTION}, {".", TK_DOT},
        {"<", TK_LT}, {">", TK_GT}, {"~", TK_TILDE}, {"&", TK_AMP}, {"|", TK_PIPE},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        uint32_t n = table[i].text[1] ? 2 : 1;
        if (peek_at(lx, 0) == table[i].text[0] && (n == 1 || peek_at(lx, 1) == table[i].text[1])) {
            tok->kind = table[i].kind;
            lx->pos += n;
            return true;
        }
    }
    return false;
}

mcsg_status scad_lex(scad_lexer *lx, scad_token *tok, mcsg_error *err)
{
    mcsg_status st;
    int c;
    if (lx->pos == 0 && lx->size >= 3 && memcmp(lx->text, "\xEF\xBB\xBF", 3) == 0)
        lx->pos = lx->line_start = 3;
    st = skip_space(lx, err);
    if (st != MCSG_OK)
        return st;
    memset(tok, 0, sizeof *tok);
    tok->line = lx->line;
    tok->col = column(lx);
    tok->start = lx->pos;
    c = peek_at(lx, 0);
    if (c < 0) {
        tok->kind = TK_EOF;
    } else if (is_digit(c) || (c == '.' && is_digit(peek_at(lx, 1)))) {
        st = lex_number(lx, tok, err);
    } else if (c == '"') {
        st = lex_string(lx, tok, err);
    } else if (is_alpha(c) || (c == '$' && is_alpha(peek_at(lx, 1)))) {
        lx->pos++;
        while (is_ident_char(peek_at(lx, 0)))
            lx->pos++;
        tok->kind = TK_IDENT;
    } else if (!lex_punct(lx, tok)) {
        return scad_fail_at(lx->name, tok->line, tok->col, err, MCSG_ERR_PARSE,
                            (c >= 0x21 && c < 0x7F) ? "unexpected character `%c`"
                                                     : "unexpected byte 0x%02X", c);
    }
    tok->len = lx->pos - tok->start;
    return st;
}

void scad_describe_token(const scad_lexer *lx, const scad_token *tok, char *buf, size_t size)
{
    switch (tok->kind) {
    case TK_EOF: snprintf(buf, size, "end of file"); break;
    case TK_NUMBER: snprintf(buf, size, "number `%.*s`", (int)(tok->len > 24 ? 24 : tok->len),
                             lx->text + tok->start); break;
    case TK_STRING: snprintf(buf, size, "a string"); break;
    default:
        snprintf(buf, size, "`%.*s`", (int)(tok->len > 40 ? 40 : tok->len), lx->text + tok->start);
        break;
    }
}
