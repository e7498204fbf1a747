#define _POSIX_C_SOURCE 200809L
/* Recursive-descent JSON reader; depth is bounded by JSON_MAX_DEPTH. Its
 * memory is counted against the command line's budget (budget.h). */
#include "json.h"

#include "budget.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct reader {
    const char *s;
    size_t len, pos;
    char *err;
    size_t err_len;
    int failed;
    const char *defer; /* the root member whose array is not built, or NULL */
};

static void fail(struct reader *r, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (r->failed)
        return;
    r->failed = 1;
    n = snprintf(r->err, r->err_len, "at byte %zu: ", r->pos);
    va_start(ap, fmt);
    if (n >= 0 && (size_t)n < r->err_len)
        vsnprintf(r->err + n, r->err_len - (size_t)n, fmt, ap);
    va_end(ap);
}

static void skip_space(struct reader *r)
{
    while (r->pos < r->len && (r->s[r->pos] == ' ' || r->s[r->pos] == '\t' ||
                               r->s[r->pos] == '\n' || r->s[r->pos] == '\r'))
        r->pos++;
}

static int peek(struct reader *r)
{
    return r->pos < r->len ? (unsigned char)r->s[r->pos] : -1;
}

static int parse_value(struct reader *r, struct json *out, int depth);

static int parse_literal(struct reader *r, const char *word)
{
    size_t n = strlen(word);
    if (r->len - r->pos < n || memcmp(r->s + r->pos, word, n) != 0) {
        fail(r, "unexpected character '%c'", r->s[r->pos]);
        return 0;
    }
    r->pos += n;
    return 1;
}

static int parse_number(struct reader *r, struct json *out)
{
    size_t start = r->pos;
    char buf[64], *end;
    /* validate the JSON number grammar before strtod sees it */
    if (peek(r) == '-')
        r->pos++;
    if (peek(r) == '0') {
        r->pos++;
    } else if (peek(r) >= '1' && peek(r) <= '9') {
        while (peek(r) >= '0' && peek(r) <= '9')
            r->pos++;
    } else {
        fail(r, "invalid number");
        return 0;
    }
    if (peek(r) == '.') {
        r->pos++;
        if (!(peek(r) >= '0' && peek(r) <= '9')) {
            fail(r, "invalid number: digit expected after '.'");
            return 0;
        }
        while (peek(r) >= '0' && peek(r) <= '9')
            r->pos++;
    }
    if (peek(r) == 'e' || peek(r) == 'E') {
        r->pos++;
        if (peek(r) == '+' || peek(r) == '-')
            r->pos++;
        if (!(peek(r) >= '0' && peek(r) <= '9')) {
            fail(r, "invalid number: digit expected in exponent");
            return 0;
        }
        while (peek(r) >= '0' && peek(r) <= '9')
            r->pos++;
    }
    if (r->pos - start >= sizeof buf) {
        r->pos = start;
        fail(r, "number too long");
        return 0;
    }
    memcpy(buf, r->s + start, r->pos - start);
    buf[r->pos - start] = '\0';
    errno = 0;
    out->type = JSON_NUMBER;
    out->number = strtod(buf, &end);
    if (!isfinite(out->number)) {
        r->pos = start;
        fail(r, "number %s is out of range", buf);
        return 0;
    }
    return 1;
}

static int hex_digit(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static size_t put_utf8(char *dst, unsigned long cp)
{
    if (cp < 0x80) {
        dst[0] = (char)cp;
        return 1;
    }
    if (cp < 0x800) {
        dst[0] = (char)(0xC0 | (cp >> 6));
        dst[1] = (char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        dst[0] = (char)(0xE0 | (cp >> 12));
        dst[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        dst[2] = (char)(0x80 | (cp & 0x3F));
        return 3;
    }
    dst[0] = (char)(0xF0 | (cp >> 18));
    dst[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
    dst[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
    dst[3] = (char)(0x80 | (cp & 0x3F));
    return 4;
}

static int read_hex4(struct reader *r, unsigned long *cp)
{
    int i;
    *cp = 0;
    for (i = 0; i < 4; i++) {
        int h = hex_digit(peek(r));
        if (h < 0) {
            fail(r, "invalid \\u escape");
            return 0;
        }
        *cp = *cp * 16 + (unsigned long)h;
        r->pos++;
    }
    return 1;
}

static char *parse_string(struct reader *r)
{
    /* the decoded string is never longer than its source */
    size_t start = ++r->pos, n = 0;
    char *buf;
    while (r->pos < r->len && r->s[r->pos] != '"') {
        if (r->s[r->pos] == '\\')
            r->pos++;
        r->pos++;
    }
    if (r->pos >= r->len) {
        r->pos = start - 1;
        fail(r, "unterminated string");
        return NULL;
    }
    buf = budget_malloc(r->pos - start + 1);
    if (!buf) {
        fail(r, "out of memory");
        return NULL;
    }
    r->pos = start;
    while (r->s[r->pos] != '"') {
        unsigned char c = (unsigned char)r->s[r->pos++];
        unsigned long cp;
        if (c < 0x20) {
            r->pos--;
            fail(r, "control character in string");
            budget_free(buf);
            return NULL;
        }
        if (c != '\\') {
            buf[n++] = (char)c;
            continue;
        }
        c = (unsigned char)r->s[r->pos++];
        switch (c) {
        case '"':
        case '\\':
        case '/':
            buf[n++] = (char)c;
            break;
        case 'b':
            buf[n++] = '\b';
            break;
        case 'f':
            buf[n++] = '\f';
            break;
        case 'n':
            buf[n++] = '\n';
            break;
        case 'r':
            buf[n++] = '\r';
            break;
        case 't':
            buf[n++] = '\t';
            break;
        case 'u':
            if (!read_hex4(r, &cp) || cp == 0 ||
                (cp >= 0xD800 && cp < 0xE000)) {
                if (!r->failed)
                    fail(r, "\\u escape not supported here (NUL or surrogate)");
                budget_free(buf);
                return NULL;
            }
            n += put_utf8(buf + n, cp);
            break;
        default:
            r->pos--;
            fail(r, "invalid escape '\\%c'", c);
            budget_free(buf);
            return NULL;
        }
    }
    r->pos++;
    buf[n] = '\0';
    return buf;
}

/* Append v to a growing array; *cap doubles as needed. */
static int push(struct reader *r, struct json **items, size_t *count,
                size_t *cap, const struct json *v)
{
    if (*count == *cap) {
        size_t ncap = *cap ? *cap * 2 : 4;
        struct json *grown = budget_realloc(*items, ncap * sizeof **items);
        if (!grown) {
            fail(r, "out of memory");
            return 0;
        }
        *items = grown;
        *cap = ncap;
    }
    (*items)[(*count)++] = *v;
    return 1;
}

static void free_children(struct json *j);

/* After an array item or object member: 1 if another follows (a comma
 * was eaten), 0 if close ends the container (eaten too), -1 on error. */
static int next_item(struct reader *r, char close, const char *what)
{
    skip_space(r);
    if (peek(r) == ',') {
        r->pos++;
        return 1;
    }
    if (peek(r) == close) {
        r->pos++;
        return 0;
    }
    if (peek(r) < 0)
        fail(r, "unexpected end of input in %s", what);
    else
        fail(r, "expected ',' or '%c' in %s", close, what);
    return -1;
}

/* An array, its items kept; or, with skim, each item checked and freed as
 * soon as it is read, the node getting the count and where the array
 * starts (json_each_item reads it again; memory: one item's tree). One
 * item loop for both, so a skimmed array is refused exactly where a kept
 * one is. Inline: a scene's every point is an array, and a call for each
 * would be most of what reading one costs. */
static inline int read_array(struct reader *r, struct json *out, int depth,
                             int skim)
{
    size_t cap = 0;
    out->type = JSON_ARRAY;
    if (skim) {
        out->deferred = 1;
        out->number = (double)r->pos; /* exact: offsets are far below 2^53 */
    }
    r->pos++;
    skip_space(r);
    if (peek(r) == ']') {
        r->pos++;
        return 1;
    }
    for (;;) {
        struct json v;
        int ok;
        memset(&v, 0, sizeof v);
        ok = parse_value(r, &v, depth + 1);
        if (ok && skim)
            out->count++;
        else if (ok)
            ok = push(r, &out->items, &out->count, &cap, &v);
        if (!ok || skim) /* else v's tree is the array's now */
            free_children(&v);
        if (!ok)
            return 0;
        switch (next_item(r, ']', "array")) {
        case 1:
            continue;
        case 0:
            return 1;
        default:
            return 0;
        }
    }
}

static int parse_object(struct reader *r, struct json *out, int depth)
{
    size_t cap = 0, key_cap = 0;
    out->type = JSON_OBJECT;
    r->pos++;
    skip_space(r);
    if (peek(r) == '}') {
        r->pos++;
        return 1;
    }
    for (;;) {
        struct json v;
        char *key;
        size_t i;
        skip_space(r);
        if (peek(r) != '"') {
            fail(r, peek(r) < 0 ? "unexpected end of input in object"
                                : "expected a string key");
            return 0;
        }
        key = parse_string(r);
        if (!key)
            return 0;
        for (i = 0; i < out->count; i++)
            if (strcmp(out->keys[i], key) == 0) {
                fail(r, "duplicate key \"%s\"", key);
                budget_free(key);
                return 0;
            }
        if (out->count == key_cap) {
            size_t ncap = key_cap ? key_cap * 2 : 4;
            char **grown = budget_realloc(out->keys, ncap * sizeof *grown);
            if (!grown) {
                budget_free(key);
                fail(r, "out of memory");
                return 0;
            }
            out->keys = grown;
            key_cap = ncap;
        }
        skip_space(r);
        if (peek(r) != ':') {
            budget_free(key);
            fail(r, "expected ':' after key");
            return 0;
        }
        r->pos++;
        memset(&v, 0, sizeof v);
        skip_space(r);
        if (depth == 0 && r->defer && peek(r) == '[' &&
            strcmp(key, r->defer) == 0) {
            if (!read_array(r, &v, depth + 1, 1)) {
                budget_free(key);
                free_children(&v);
                return 0;
            }
        } else if (!parse_value(r, &v, depth + 1)) {
            budget_free(key);
            free_children(&v);
            return 0;
        }
        out->keys[out->count] = key;
        if (!push(r, &out->items, &out->count, &cap, &v)) {
            budget_free(key);
            free_children(&v);
            return 0;
        }
        switch (next_item(r, '}', "object")) {
        case 1:
            continue;
        case 0:
            return 1;
        default:
            return 0;
        }
    }
}

static int parse_value(struct reader *r, struct json *out, int depth)
{
    int c;
    if (depth > JSON_MAX_DEPTH) {
        fail(r, "nesting deeper than %d", JSON_MAX_DEPTH);
        return 0;
    }
    skip_space(r);
    c = peek(r);
    switch (c) {
    case -1:
        fail(r, "unexpected end of input");
        return 0;
    case '{':
        return parse_object(r, out, depth);
    case '[':
        return read_array(r, out, depth, 0);
    case '"':
        out->type = JSON_STRING;
        out->string = parse_string(r);
        return out->string != NULL;
    case 't':
        out->type = JSON_BOOL;
        out->number = 1;
        return parse_literal(r, "true");
    case 'f':
        out->type = JSON_BOOL;
        return parse_literal(r, "false");
    case 'n':
        out->type = JSON_NULL;
        return parse_literal(r, "null");
    default:
        if (c == '-' || (c >= '0' && c <= '9'))
            return parse_number(r, out);
        fail(r, "unexpected character '%c'", c);
        return 0;
    }
}

static void free_children(struct json *j)
{
    size_t i, n = j->items ? j->count : 0; /* a deferred array has none */
    for (i = 0; i < n; i++) {
        free_children(&j->items[i]);
        if (j->keys)
            budget_free(j->keys[i]);
    }
    budget_free(j->items);
    budget_free(j->keys);
    budget_free(j->string);
}

void json_free(struct json *j)
{
    if (!j)
        return;
    free_children(j);
    budget_free(j);
}

static struct json *parse_document(const char *text, size_t len,
                                   const char *defer, char *err, size_t err_len)
{
    struct reader r;
    struct json *root = budget_malloc(sizeof *root);
    r.s = text;
    r.len = len;
    r.pos = 0;
    r.err = err;
    r.err_len = err_len;
    r.failed = 0;
    r.defer = defer;
    if (!root) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    memset(root, 0, sizeof *root);
    if (parse_value(&r, root, 0)) {
        skip_space(&r);
        if (r.pos < r.len)
            fail(&r, "trailing characters after the document");
    }
    if (r.failed) {
        json_free(root);
        return NULL;
    }
    return root;
}

struct json *json_parse(const char *text, size_t len, char *err, size_t err_len)
{
    return parse_document(text, len, NULL, err, err_len);
}

struct json *json_parse_deferring(const char *text, size_t len,
                                  const char *defer, char *err, size_t err_len)
{
    return parse_document(text, len, defer, err, err_len);
}

int json_each_item(const char *text, size_t len, const struct json *array,
                   int (*fn)(void *ctx, size_t i, const struct json *item),
                   void *ctx, char *err, size_t err_len)
{
    struct reader r;
    size_t i;
    if (!array->deferred) {
        for (i = 0; i < array->count; i++)
            if (fn(ctx, i, &array->items[i]))
                return -1;
        return 0;
    }
    r.s = text;
    r.len = len;
    r.pos = (size_t)array->number + 1;
    r.err = err;
    r.err_len = err_len;
    r.failed = 0;
    r.defer = NULL;
    for (i = 0; i < array->count; i++) {
        struct json v;
        int stop;
        memset(&v, 0, sizeof v);
        if (i > 0 && next_item(&r, ']', "array") != 1)
            return -1; /* the text is not what was skimmed */
        if (!parse_value(&r, &v, 2)) {
            free_children(&v);
            return -1;
        }
        stop = fn(ctx, i, &v);
        free_children(&v);
        if (stop)
            return -1;
    }
    return 0;
}

const struct json *json_get(const struct json *obj, const char *key)
{
    size_t i;
    if (!obj || obj->type != JSON_OBJECT)
        return NULL;
    for (i = 0; i < obj->count; i++)
        if (strcmp(obj->keys[i], key) == 0)
            return &obj->items[i];
    return NULL;
}

const char *json_type_name(enum json_type t)
{
    static const char *const names[] = {"null",   "boolean", "number",
                                        "string", "array",   "object"};
    return names[t];
}
