/*
 * Command-line options of the meshcsg tool: one table per command, which both the parser
 * and the help text read, so that what `meshcsg CMD --help` lists is what is accepted.
 *
 * Accepted forms: `--name VALUE`, `--name=VALUE`, `-x VALUE`, `-xVALUE`, flags `--name`
 * and `-x`; `--` ends the options (later arguments are operands even if they start with
 * '-'). An unknown option, a missing or malformed value, a number out of range, or the
 * wrong number of operands is a usage error: one line naming the option on stderr,
 * exit status 2.
 */
#ifndef MCSG_CLI_OPTIONS_H
#define MCSG_CLI_OPTIONS_H

#include <stddef.h>
#include <stdio.h>

#define CLI_EXIT_PROBLEM 1
#define CLI_EXIT_USAGE 2
#define CLI_EXIT_BROKEN_GUARANTEE 3 /* eval: the result was written but breaks a guarantee */

typedef enum cli_kind {
    CLI_FLAG,   /* no value: sets an int to 1 */
    CLI_STRING, /* a value kept as given */
    CLI_NUMBER  /* a decimal integer in [min, max] */
} cli_kind;

typedef struct cli_option {
    const char *name;       /* long name without dashes ("threads") */
    char short_name;        /* 'o', or 0 for none */
    cli_kind kind;
    const char *value_name; /* "N", "FILE" (ignored for flags) */
    long min, max;          /* CLI_NUMBER's range */
    size_t offset;          /* of the int, long or const char * in cli_values */
    const char *help;       /* what it does; ends with its default where it has one */
} cli_option;

/* Everything any command's options can set; zero and NULL are the defaults. */
typedef struct cli_values {
    const char *output;
    const char *format;
    const char *picture, *view, *size; /* --picture FILE, --view V, --size WxH */
    int edges;
    int self_intersections, stats, check_inputs, check_crossings, keep_all_vertices, verbose;
    int quiet;
    long threads, spheres;
} cli_values;

typedef struct cli_command {
    const char *name;
    const char *operands;       /* "FILE...", "IN OUT" */
    const char *summary;        /* one line */
    const char *description;    /* a few lines shown by CMD --help, or NULL */
    const cli_option *options;  /* terminated by an entry with name NULL */
    int min_operands, max_operands; /* max -1: no limit */
    int (*run)(const cli_values *values, int operand_count, char **operands);
} cli_command;

/* Parses argv (the arguments after the command name) for `cmd`: fills *values and moves
 * the operands, in order, to the front of argv; returns their count. Returns -1 after
 * printing a usage error, and -2 when --help or -h was given (the help is printed on
 * stdout). */
int cli_parse(const cli_command *cmd, int argc, char **argv, cli_values *values);

/* `meshcsg CMD --help`: usage line, description and every option with its default. */
void cli_print_command_help(FILE *out, const cli_command *cmd);

/* `meshcsg --help`: every command's usage line and summary. */
void cli_print_help(FILE *out, const char *version, const cli_command *commands,
                    size_t count);

#endif
