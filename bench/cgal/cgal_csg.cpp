// The peer in `make bench`: a CSG scene evaluated with CGAL's corefinement, one boolean
// operation at a time (CGAL has no n-ary or whole-tree evaluation), so that meshcsg's
// times can be reported as ratios against the best-known general library.
//
// usage: cgal_csg TREE.sexp [-o RESULT.off] [--exact]
//
// TREE.sexp is the scene description written by ../shared/scenes/make_scenes.py:
// (union|difference|intersection CHILD...) with OFF file names (relative to the tree's
// folder) as leaves. An n-ary node is folded from the left: (difference a b c) is
// (a - b) - c. The default kernel is Exact_predicates_inexact_constructions (what CGAL
// users pick for speed: exact decisions, rounded new points); --exact uses the exact
// constructions kernel, which CGAL recommends for chained operations.
//
// Prints, on success: "read S s", "evaluate S s", "write S s", "operations N",
// "result faces F volume V". Exits 2 with a message when an operation fails.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

struct Node {
    std::string op;    // empty for a leaf
    std::string file;  // leaf only
    std::vector<std::unique_ptr<Node>> children;
};

class SexpReader {
public:
    explicit SexpReader(std::string text) : text_(std::move(text)) {}

    std::unique_ptr<Node> read_tree()
    {
        std::unique_ptr<Node> root = read_node();
        skip_space();
        if (pos_ != text_.size())
            fail("text after the tree");
        return root;
    }

private:
    std::string text_;
    size_t pos_ = 0;

    [[noreturn]] void fail(const std::string &what) const
    {
        throw std::runtime_error("tree.sexp, offset " + std::to_string(pos_) + ": " + what);
    }

    void skip_space()
    {
        while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_])))
            pos_++;
    }

    std::string read_word()
    {
        size_t start = pos_;
        while (pos_ < text_.size() && text_[pos_] != '(' && text_[pos_] != ')' &&
               !std::isspace(static_cast<unsigned char>(text_[pos_])))
            pos_++;
        if (start == pos_)
            fail("expected a name");
        return text_.substr(start, pos_ - start);
    }

    std::unique_ptr<Node> read_node()
    {
        auto node = std::make_unique<Node>();
        skip_space();
        if (pos_ >= text_.size())
            fail("unexpected end");
        if (text_[pos_] != '(') {
            node->file = read_word();
            return node;
        }
        pos_++;
        skip_space();
        node->op = read_word();
        if (node->op != "union" && node->op != "difference" && node->op != "intersection")
            fail("unknown operation '" + node->op + "'");
        for (;;) {
            skip_space();
            if (pos_ < text_.size() && text_[pos_] == ')')
                break;
            node->children.push_back(read_node());
        }
        pos_++;
        if (node->children.empty())
            fail("operation without operands");
        return node;
    }
};

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <class Kernel> class Evaluator {
public:
    using Mesh = CGAL::Surface_mesh<typename Kernel::Point_3>;

    explicit Evaluator(std::string folder) : folder_(std::move(folder)) {}

    // Reads every leaf first, so that parsing is timed apart from the operations.
    void read_leaves(const Node &node)
    {
        if (node.op.empty()) {
            Mesh mesh;
            std::string path = folder_ + "/" + node.file;
            if (!CGAL::IO::read_polygon_mesh(path, mesh) || !CGAL::is_triangle_mesh(mesh))
                throw std::runtime_error("cannot read a triangle mesh from " + path);
            leaves_.push_back(std::move(mesh));
            return;
        }
        for (const auto &child : node.children)
            read_leaves(*child);
    }

    Mesh evaluate(const Node &node)
    {
        next_leaf_ = 0;
        return eval_node(node);
    }

    size_t operations() const { return operations_; }

private:
    std::string folder_;
    std::vector<Mesh> leaves_;
    size_t next_leaf_ = 0, operations_ = 0;

    Mesh eval_node(const Node &node)
    {
        if (node.op.empty())
            return std::move(leaves_[next_leaf_++]);
        Mesh acc = eval_node(*node.children[0]);
        for (size_t i = 1; i < node.children.size(); i++) {
            Mesh rhs = eval_node(*node.children[i]);
            Mesh out;
            bool ok = node.op == "union" ? PMP::corefine_and_compute_union(acc, rhs, out)
                      : node.op == "difference"
                          ? PMP::corefine_and_compute_difference(acc, rhs, out)
                          : PMP::corefine_and_compute_intersection(acc, rhs, out);
            operations_++;
            if (!ok)
                throw std::runtime_error("corefinement " + node.op + " failed at operation " +
                                         std::to_string(operations_));
            acc = std::move(out);
        }
        return acc;
    }
};

template <class Kernel> int run(const std::string &tree_path, const char *out_path)
{
    std::ifstream in(tree_path);
    if (!in)
        throw std::runtime_error("cannot open " + tree_path);
    std::stringstream text;
    text << in.rdbuf();
    std::unique_ptr<Node> tree = SexpReader(text.str()).read_tree();
    size_t slash = tree_path.find_last_of('/');
    std::string folder = slash == std::string::npos ? "." : tree_path.substr(0, slash);

    Evaluator<Kernel> evaluator(folder);
    auto start = std::chrono::steady_clock::now();
    evaluator.read_leaves(*tree);
    std::printf("read %.6f s\n", seconds_since(start));
    start = std::chrono::steady_clock::now();
    typename Evaluator<Kernel>::Mesh result = evaluator.evaluate(*tree);
    std::printf("evaluate %.6f s\n", seconds_since(start));
    start = std::chrono::steady_clock::now();
    if (out_path && !CGAL::IO::write_polygon_mesh(out_path, result,
                                                 CGAL::parameters::stream_precision(17)))
        throw std::runtime_error(std::string("cannot write ") + out_path);
    std::printf("write %.6f s\n", seconds_since(start));
    std::printf("operations %zu\n", evaluator.operations());
    std::printf("result faces %zu volume %.15g\n", static_cast<size_t>(result.number_of_faces()),
                CGAL::to_double(PMP::volume(result)));
    return 0;
}

}  // namespace

int main(int argc, char **argv)
{
    const char *tree = nullptr, *out = nullptr;
    bool exact = false;
    for (int i = 1; i < argc; i++) {
        if (std::strcmp(argv[i], "-o") == 0 && i + 1 < argc)
            out = argv[++i];
        else if (std::strcmp(argv[i], "--exact") == 0)
            exact = true;
        else if (!tree && argv[i][0] != '-')
            tree = argv[i];
        else {
            std::fprintf(stderr, "usage: cgal_csg TREE.sexp [-o RESULT.off] [--exact]\n");
            return 1;
        }
    }
    if (!tree) {
        std::fprintf(stderr, "usage: cgal_csg TREE.sexp [-o RESULT.off] [--exact]\n");
        return 1;
    }
    try {
        return exact ? run<CGAL::Exact_predicates_exact_constructions_kernel>(tree, out)
                     : run<CGAL::Exact_predicates_inexact_constructions_kernel>(tree, out);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_csg: %s\n", e.what());
        return 2;
    }
}
