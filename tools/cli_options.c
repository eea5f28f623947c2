/*
 * The option parser and help printer of the meshcsg tool (cli_options.h). A small table
 * parser rather than getopt_long: the same tables give the help text, and numbers are
 * checked whole (strtol with an end check and a range), never through atoi.
 */
#include "cli_options.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

static void usage_error(const cli_command *cmd, const char *what, const char *arg)
{
    fprintf(stderr, "meshcsg %s: %s%s%s (see meshcsg %s --help)\n", cmd->name, what,
            arg ? ": " : "", arg ? arg : "", cmd->name);
}

static const cli_option *find_long(const cli_option *opts, const char *name, size_t len)
{
    for (; opts->name; opts++)
        if (strlen(opts->name) == len && strncmp(opts->name, name, len) == 0)
            return opts;
    return NULL;
}

static const cli_option *find_short(const cli_option *opts, char c)
{
    for (; opts->name; opts++)
        if (opts->short_name && opts->short_name == c)
            return opts;
    return NULL;
}

/* "--threads" or "-o": how the option was written, for messages. */
static void option_spelling(const cli_option *o, int as_short, char *buf, size_t size)
{
    if (as_short)
        snprintf(buf, size, "-%c", o->short_name);
    else
        snprintf(buf, size, "--%s", o->name);
}

static int parse_number(const char *text, long min, long max, long *out)
{
    char *end;
    long v;
    if (!*text || *text == ' ' || *text == '+')
        return 0;
    errno = 0;
    v = strtol(text, &end, 10);
    if (errno || *end || v < min || v > max)
        return 0;
    *out = v;
    return 1;
}

/* Stores `value` for option `o`; 0 after a usage error. */
static int store(const cli_command *cmd, const cli_option *o, int as_short, const char *value,
                 cli_values *values)
{
    char name[64], what[160];
    char *field = (char *)values + o->offset;
    option_spelling(o, as_short, name, sizeof name);
    if (o->kind == CLI_FLAG) {
        *(int *)(void *)field = 1;
        return 1;
    }
    if (!value) {
        snprintf(what, sizeof what, "%s needs a value (%s)", name, o->value_name);
        usage_error(cmd, what, NULL);
        return 0;
    }
    if (o->kind == CLI_STRING) {
        *(const char **)(void *)field = value;
        return 1;
    }
    if (!parse_number(value, o->min, o->max, (long *)(void *)field)) {
        snprintf(what, sizeof what, "%s takes a whole number from %ld to %ld", name, o->min,
                 o->max);
        usage_error(cmd, what, value);
        return 0;
    }
    return 1;
}

static void takes_no_value(const cli_command *cmd, const cli_option *o, int as_short,
                           const char *arg)
{
    char name[64], what[96];
    option_spelling(o, as_short, name, sizeof name);
    snprintf(what, sizeof what, "%s takes no value", name);
    usage_error(cmd, what, arg);
}

/* One "--name[=value]" argument at argv[*i]; 0 after a usage error. */
static int parse_long(const cli_command *cmd, int argc, char **argv, int *i,
                      cli_values *values)
{
    const char *arg = argv[*i] + 2, *eq = strchr(arg, '=');
    size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
    const cli_option *o = find_long(cmd->options, arg, len);
    if (!o) {
        usage_error(cmd, "unknown option", argv[*i]);
        return 0;
    }
    if (o->kind == CLI_FLAG) {
        if (eq) {
            takes_no_value(cmd, o, 0, argv[*i]);
            return 0;
        }
        return store(cmd, o, 0, NULL, values);
    }
    if (eq)
        return store(cmd, o, 0, eq + 1, values);
    return store(cmd, o, 0, *i + 1 < argc ? argv[++*i] : NULL, values);
}

/* One "-x[value]" argument at argv[*i]; 0 after a usage error. */
static int parse_short(const cli_command *cmd, int argc, char **argv, int *i,
                       cli_values *values)
{
    const cli_option *o = find_short(cmd->options, argv[*i][1]);
    const char *rest = argv[*i] + 2;
    if (!o) {
        usage_error(cmd, "unknown option", argv[*i]);
        return 0;
    }
    if (o->kind == CLI_FLAG) {
        if (*rest) {
            takes_no_value(cmd, o, 1, argv[*i]);
            return 0;
        }
        return store(cmd, o, 1, NULL, values);
    }
    if (*rest)
        return store(cmd, o, 1, rest, values);
    return store(cmd, o, 1, *i + 1 < argc ? argv[++*i] : NULL, values);
}

static int is_help(const char *arg)
{
    return strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0;
}

static int check_operand_count(const cli_command *cmd, int count)
{
    char what[160];
    if (count >= cmd->min_operands && (cmd->max_operands < 0 || count <= cmd->max_operands))
        return 1;
    snprintf(what, sizeof what, "%s (usage: meshcsg %s [OPTIONS]%s%s)",
             count < cmd->min_operands ? "missing operand" : "too many operands", cmd->name,
             *cmd->operands ? " " : "", cmd->operands);
    usage_error(cmd, what, NULL);
    return 0;
}

int cli_parse(const cli_command *cmd, int argc, char **argv, cli_values *values)
{
    int operands = 0, options_done = 0;
    memset(values, 0, sizeof *values);
    for (int i = 0; i < argc; i++) {
        const char *arg = argv[i];
        int ok = 1;
        if (options_done || arg[0] != '-' || arg[1] == '\0') {
            argv[operands++] = argv[i];
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            options_done = 1;
            continue;
        }
        if (is_help(arg)) {
            cli_print_command_help(stdout, cmd);
            return -2;
        }
        ok = arg[1] == '-' ? parse_long(cmd, argc, argv, &i, values)
                           : parse_short(cmd, argc, argv, &i, values);
        if (!ok)
            return -1;
    }
    return check_operand_count(cmd, operands) ? operands : -1;
}

#define HELP_WIDTH 80
#define HELP_COLUMN 28

/* `text` from column `col`, wrapped at word boundaries to HELP_WIDTH, continuation
 * lines indented by `indent`; ends the line. */
static void print_wrapped(FILE *out, const char *text, int col, int indent)
{
    int first = 1;
    while (*text) {
        size_t word = strcspn(text, " ");
        if (!first && col + 1 + (int)word > HELP_WIDTH) {
            fprintf(out, "\n%*s", indent, "");
            col = indent;
        } else if (!first) {
            fputc(' ', out);
            col++;
        }
        fwrite(text, 1, word, out);
        col += (int)word;
        text += word;
        while (*text == ' ')
            text++;
        first = 0;
    }
    fputc('\n', out);
}

/* "  LEFT" padded to HELP_COLUMN, then `text` wrapped (LEFT may be longer: the text then
 * starts on the next line). */
static void print_entry(FILE *out, const char *left, const char *text)
{
    int col = fprintf(out, "  %s", left);
    if (col >= HELP_COLUMN) {
        fputc('\n', out);
        col = 0;
    }
    fprintf(out, "%*s", HELP_COLUMN - col, "");
    print_wrapped(out, text, HELP_COLUMN, HELP_COLUMN);
}

/* "-o, --output FILE" and the option's help. */
static void print_option(FILE *out, const cli_option *o)
{
    char left[64];
    int n = 0;
    if (o->short_name)
        n = snprintf(left, sizeof left, "-%c, ", o->short_name);
    else
        n = snprintf(left, sizeof left, "    ");
    snprintf(left + n, sizeof left - (size_t)n, "--%s%s%s", o->name,
             o->kind == CLI_FLAG ? "" : " ", o->kind == CLI_FLAG ? "" : o->value_name);
    print_entry(out, left, o->help);
}

void cli_print_command_help(FILE *out, const cli_command *cmd)
{
    fprintf(out, "usage: meshcsg %s [OPTIONS]%s%s\n", cmd->name, *cmd->operands ? " " : "",
            cmd->operands);
    print_wrapped(out, cmd->summary, 0, 0);
    if (cmd->description)
        fprintf(out, "\n%s\n", cmd->description);
    fprintf(out, "\noptions:\n");
    for (const cli_option *o = cmd->options; o->name; o++)
        print_option(out, o);
    print_entry(out, "-h, --help", "print this help and exit");
}

void cli_print_help(FILE *out, const char *version, const cli_command *commands,
                    size_t count)
{
    fprintf(out, "meshcsg %s - exact CSG on closed triangle meshes\n\n"
                 "usage: meshcsg COMMAND [OPTIONS] OPERANDS...\n\ncommands:\n", version);
    for (size_t i = 0; i < count; i++) {
        char left[64];
        snprintf(left, sizeof left, "%s %s", commands[i].name, commands[i].operands);
        print_entry(out, left, commands[i].summary);
    }
    fprintf(out, "\n'meshcsg COMMAND --help' lists the options of a command.\n");
    print_entry(out, "-h, --help", "print this help and exit");
    print_entry(out, "--version", "print the version and exit");
    fprintf(out, "\nexit status: 0 success (check: every mesh valid); 1 a problem was found "
                 "or an\noperation failed; 2 usage error; 3 (eval, repair) the result was "
                 "written but\nrounding to doubles broke one of its guarantees (a warning "
                 "says which)\n");
}
