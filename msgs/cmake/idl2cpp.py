#!/usr/bin/env python3
"""Generates cairn's C++ message structs and their Cyclone DDS type support from OMG IDL.

The IDL under msgs/idl is the single source of truth. idlc turns each file into C types and a
dds_topic_descriptor_t; this script turns the same file into
  <out>/include/<pkg>/<kind>/<Name>.hpp   idiomatic C++ struct (std::string, std::vector, std::array)
  <out>/src/<pkg>/<kind>/<Name>.cpp       XCDR1 codec straight from/into the C++ struct (what cairn puts
                                          on the wire), conversion C++ <-> idlc C struct (kept for tests
                                          that compare the bytes with idlc's serializer), printing,
                                          registration
Only the IDL subset cairn uses is accepted (modules, const, @final struct, @default, primitive types,
string, sequence<T[,N]>, fixed arrays, nested structs); anything else is an error naming file:line.
"""
import os
import re
import sys

PRIM = {
    'float': 'float', 'double': 'double', 'boolean': 'bool', 'octet': 'uint8_t', 'char': 'char',
    'int8': 'int8_t', 'uint8': 'uint8_t', 'int16': 'int16_t', 'uint16': 'uint16_t',
    'int32': 'int32_t', 'uint32': 'uint32_t', 'int64': 'int64_t', 'uint64': 'uint64_t',
    'long': 'int32_t', 'short': 'int16_t', 'string': 'std::string',
}


class IdlError(Exception):
    pass


def tokenize(text, path):
    toks = []
    line = 1
    i = 0
    n = len(text)
    while i < n:
        c = text[i]
        if c == '\n':
            line += 1
            i += 1
        elif c.isspace():
            i += 1
        elif text.startswith('//', i):
            while i < n and text[i] != '\n':
                i += 1
        elif text.startswith('/*', i):
            j = text.find('*/', i)
            line += text.count('\n', i, j)
            i = j + 2
        elif c == '#':
            j = text.find('\n', i)
            toks.append(('pp', text[i:j].strip(), line))
            i = j
        elif c.isalnum() or c == '_' or (c in '-.' and i + 1 < n and text[i + 1].isdigit()):
            j = i + 1 if c in '-.' else i  # a leading sign or dot belongs to the number
            while j < n and (text[j].isalnum() or text[j] in '_.:' or
                             (text[j] in '-+' and j > i and text[j - 1] in 'eE' and (text[i].isdigit() or text[i] in '-.'))):
                if text[j] == ':' and not text.startswith('::', j):
                    break
                j += 2 if text.startswith('::', j) else 1
            toks.append(('id', text[i:j], line))
            i = j
        elif c == '"':
            j = text.find('"', i + 1)
            toks.append(('str', text[i:j + 1], line))
            i = j + 1
        else:
            toks.append(('p', c, line))
            i += 1
    return toks


class Parser:
    def __init__(self, path):
        self.path = path
        self.toks = tokenize(open(path).read(), path)
        self.i = 0
        self.includes = []
        self.structs = []   # (scope list, name, fields)
        self.consts = []    # (scope list, cpp type, name, value)

    def err(self, msg):
        line = self.toks[min(self.i, len(self.toks) - 1)][2] if self.toks else 1
        raise IdlError(f'{self.path}:{line}: {msg}')

    def peek(self):
        return self.toks[self.i] if self.i < len(self.toks) else ('eof', '', 0)

    def next(self):
        t = self.peek()
        self.i += 1
        return t

    def expect(self, val):
        t = self.next()
        if t[1] != val:
            self.i -= 1
            self.err(f"expected '{val}', found '{t[1]}'")
        return t

    def parse(self):
        self.body([])
        return self

    def body(self, scope):
        while True:
            t = self.peek()
            if t[0] == 'eof' or t[1] == '}':
                return
            if t[0] == 'pp':
                self.next()
                m = re.match(r'#include\s+"([^"]+)"', t[1])
                if m:
                    self.includes.append(m.group(1))
                continue
            if t[1] == 'module':
                self.next()
                name = self.next()[1]
                self.expect('{')
                self.body(scope + [name])
                self.expect('}')
                self.expect(';')
                continue
            if t[1] == 'const':
                self.next()
                typ = self.next()[1]
                name = self.next()[1].lstrip('_')
                self.expect('=')
                val = self.next()[1]
                self.expect(';')
                if typ not in PRIM:
                    self.err(f"unsupported const type '{typ}'")
                self.consts.append((scope, PRIM[typ], name, val))
                continue
            annotations = self.annotations()
            t = self.peek()
            if t[1] == 'struct':
                self.next()
                if 'appendable' in annotations or 'mutable' in annotations:
                    self.err('cairn types must be @final (XCDR1 on the wire, as ROS 2)')
                name = self.next()[1]
                self.expect('{')
                fields = []
                while self.peek()[1] != '}':
                    fields.append(self.field())
                if not fields:
                    self.err(f"empty struct '{name}' (CDR needs at least one member; ROS 2 adds a uint8)")
                if [f['name'] for f in fields] == ['request_header']:
                    # an empty ROS 2 request/reply: rosidl serializes its placeholder byte after the rmw header
                    self.err(f"'{name}' holds only the request header: an empty ROS 2 service message needs "
                             "'uint8 structure_needs_at_least_one_member;' after it (rosidl puts that byte on the wire)")
                self.expect('}')
                self.expect(';')
                self.structs.append((scope, name, fields))
                continue
            self.err(f"unsupported IDL construct '{t[1]}'")

    def annotations(self):
        ann = {}
        while self.peek()[1] == '@':
            self.next()
            name = self.next()[1]
            val = None
            if self.peek()[1] == '(':
                self.next()
                val = self.next()[1]
                self.expect(')')
            ann[name] = val
        return ann

    def field(self):
        ann = self.annotations()
        line = self.peek()[2]
        t = self.next()[1]
        seq = None
        if t == 'sequence':
            self.expect('<')
            t = self.next()[1]
            bound = None
            if self.peek()[1] == ',':
                self.next()
                bound = self.next()[1]
            self.expect('>')
            seq = bound or ''
        name = self.next()[1]
        arr = None
        if self.peek()[1] == '[':
            self.next()
            arr = self.next()[1]
            self.expect(']')
        self.expect(';')
        if t not in PRIM and '::' not in t:
            self.err(f"unknown type '{t}' (use a primitive or a fully scoped struct name)")
        return dict(type=t, name=name, seq=seq, arr=arr, default=ann.get('default'), line=line)


def cpp_struct_name(scoped):
    """'std_msgs::msg::dds_::Header_' -> 'std_msgs::msg::Header'"""
    parts = [p for p in scoped.split('::') if p != 'dds_']
    parts[-1] = parts[-1].rstrip('_')
    return '::'.join(parts)


def c_struct_name(scope, name):
    return '_'.join(scope + [name])


def c_scoped(scoped):
    return scoped.replace('::', '_')


def cpp_elem(t):
    return PRIM[t] if t in PRIM else cpp_struct_name(t)


def cpp_field_type(f):
    e = cpp_elem(f['type'])
    if f['seq'] is not None:
        if e == 'bool':
            e = 'uint8_t'  # std::vector<bool> is not contiguous; CDR boolean is one octet either way
        return f'std::vector<{e}>'
    if f['arr']:
        return f'std::array<{e}, {f["arr"]}>'
    return e


def generate(idl_path, idl_root, out_dir):
    p = Parser(idl_path).parse()
    rel = os.path.relpath(idl_path, idl_root)[:-4]  # pkg/msg/Name
    hdr_rel = rel + '.hpp'
    guard = 'CAIRN_GEN_' + re.sub(r'[^A-Za-z0-9]', '_', rel).upper() + '_HPP'
    H = []
    H.append(f'// Generated by msgs/cmake/idl2cpp.py from {rel}.idl - do not edit.')
    H.append(f'#ifndef {guard}\n#define {guard}')
    H.append('#include <array>\n#include <cstdint>\n#include <string>\n#include <vector>')
    H.append('#include "cairn/msgs/type_support.hpp"')
    for inc in p.includes:
        H.append(f'#include "{inc[:-4]}.hpp"')
    C = []
    C.append(f'// Generated by msgs/cmake/idl2cpp.py from {rel}.idl - do not edit.')
    C.append(f'#include "{hdr_rel}"')
    C.append(f'#include "{rel}.h"')
    C.append('#include "cairn/msgs/type_support_impl.hpp"')
    for scope, typ, name, val in p.consts:
        ns = '::'.join(scope)
        H.append(f'namespace {ns} {{ inline constexpr {typ} {name} = {val}; }}')
    for scope, name, fields in p.structs:
        cpp_scope = [s for s in scope if s != 'dds_']
        cname = name.rstrip('_')
        ns = '::'.join(cpp_scope)
        full = f'{ns}::{cname}'
        ctype = c_struct_name(scope, name)
        dds_name = '::'.join(scope + [name])
        ros_name = '/'.join(cpp_scope + [cname])
        H.append(f'namespace {ns} {{')
        H.append(f'/// {ros_name} (DDS type {dds_name}).')
        H.append(f'struct {cname} {{')
        for f in fields:
            init = '{}'
            if f['default'] is not None:
                init = '{' + f['default'] + '}'
            H.append(f'  {cpp_field_type(f)} {f["name"]}{init};')
        H.append(f'  bool operator==(const {cname}&) const = default;')
        H.append('};')
        H.append('}  // namespace ' + ns)
        H.append(f'template <> const cairn::msgs::TypeSupport& cairn::msgs::type_support<{full}>();')
        # conversion functions (C++ -> C borrows; C -> C++ copies)
        C.append(f'namespace cairn::msgs::gen {{')
        C.append(f'void to_c(const {full}& m, {ctype}& c, Scratch& s, Adl) {{')
        C.append('  (void)s;')
        for f in fields:
            C.append(f'  conv_to_c(m.{f["name"]}, c.{f["name"]}, s, "{ros_name}.{f["name"]}", {f["seq"] or 0});')
        C.append('}')
        C.append(f'void from_c(const {ctype}& c, {full}& m, Adl) {{')
        for f in fields:
            C.append(f'  conv_from_c(c.{f["name"]}, m.{f["name"]});')
        C.append('}')
        # XCDR1 codec straight between the C++ struct and the serialized bytes (cairn/msgs/cdr.hpp)
        C.append(f'template <class O> static void cdr_ser_{ctype}(O& o, const {full}& m) {{')
        for f in fields:
            C.append(f'  cdr_field(o, m.{f["name"]}, {f["seq"] or 0});')
        C.append('}')
        C.append(f'void cdr_field(CdrSizer& o, const {full}& m, unsigned) {{ cdr_ser_{ctype}(o, m); }}')
        C.append(f'void cdr_field(CdrWriter& o, const {full}& m, unsigned) {{ cdr_ser_{ctype}(o, m); }}')
        C.append(f'void cdr_get(CdrReader& r, {full}& m, unsigned) {{')
        for f in fields:
            getter = 'cdr_get_bools' if f['seq'] is not None and f['type'] == 'boolean' else 'cdr_get'
            C.append(f'  {getter}(r, m.{f["name"]}, {f["seq"] or 0});')
        C.append('}')
        C.append(f'void print(const {full}& m, std::ostream& o, int indent, Adl) {{')
        if not fields:
            C.append('  (void)m; (void)o; (void)indent;')
        for f in fields:
            C.append(f'  print_field(o, indent, "{f["name"]}", m.{f["name"]});')
        C.append('}')
        C.append('}  // namespace cairn::msgs::gen')
        C.append(f'template <> const cairn::msgs::TypeSupport& cairn::msgs::type_support<{full}>() {{')
        C.append(f'  static const TypeSupport ts = make_type_support<{full}, {ctype}>(')
        C.append(f'      "{dds_name}", "{ros_name}", &{ctype}_desc);')
        C.append('  return ts;')
        C.append('}')
        C.append(f'static const cairn::msgs::Registrar registrar_{ctype}{{&cairn::msgs::type_support<{full}>()}};')
    # forward declarations for the conversion of every struct used as a field, so the .cpp compiles
    # whatever the order; they live in the generated files of the types themselves.
    fwd = []
    for scope, name, fields in p.structs:
        for f in fields:
            if f['type'] not in PRIM:
                fwd.append((cpp_struct_name(f['type']), c_scoped(f['type'])))
    decl = ['namespace cairn::msgs::gen {']
    for full, ctype in sorted(set(fwd)):
        decl.append(f'void to_c(const {full}& m, {ctype}& c, Scratch& s, Adl);')
        decl.append(f'void from_c(const {ctype}& c, {full}& m, Adl);')
        decl.append(f'void print(const {full}& m, std::ostream& o, int indent, Adl);')
        decl.append(f'void cdr_field(CdrSizer& o, const {full}& m, unsigned);')
        decl.append(f'void cdr_field(CdrWriter& o, const {full}& m, unsigned);')
        decl.append(f'void cdr_get(CdrReader& r, {full}& m, unsigned);')
    decl.append('}  // namespace cairn::msgs::gen')
    C[4:4] = decl
    H.append(f'#endif  // {guard}')
    os.makedirs(os.path.dirname(os.path.join(out_dir, 'include', hdr_rel)), exist_ok=True)
    os.makedirs(os.path.dirname(os.path.join(out_dir, 'src', rel + '.cpp')), exist_ok=True)
    write_if_changed(os.path.join(out_dir, 'include', hdr_rel), '\n'.join(H) + '\n')
    write_if_changed(os.path.join(out_dir, 'src', rel + '.cpp'), '\n'.join(C) + '\n')


def write_if_changed(path, text):
    if os.path.exists(path) and open(path).read() == text:
        return
    with open(path, 'w') as f:
        f.write(text)


def main():
    if len(sys.argv) < 4:
        print('usage: idl2cpp.py <idl_root> <out_dir> <file.idl>...', file=sys.stderr)
        return 2
    root, out = sys.argv[1], sys.argv[2]
    try:
        for f in sys.argv[3:]:
            generate(f, root, out)
    except IdlError as e:
        print(f'idl2cpp: {e}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
