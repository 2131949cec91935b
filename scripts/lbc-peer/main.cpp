// lbc-peer driver: runs the LBC authors' own solver (github.com/bldeng/LBC,
// DataSetup + LBCSolver) headless, doing for one 2-D cage what their Qt UI does
// (LBCUI.cpp), and exports the problem and the result so that c2warp's LBC can
// be run and scored on the very same mesh.
//
// What comes from upstream unchanged:
//   * LBCUI::read_cage, LBCUI::delaunay_Triangulation, LBCUI::domain_area are
//     cut out of upstream LBCUI.cpp by build.sh (lbcui_extract.inc) and compiled
//     here as members of a Qt-free LBCUI class with the same data members;
//   * DataSetup.cpp / LBCSolver.cpp are compiled as they are, except for a
//     timestamp patch (datasetup-timers.patch) that only records omp_get_wtime()
//     between the stages of DataSetup::init.
// What is re-typed here: the body of LBCUI::lbc_solver (LBCUI.cpp:280-368),
// split so that each stage can be timed and the DataSetup kept for export, and
// the UI's default solver parameters (glwidget.cpp:37-102).
//
// Usage:
//   lbc-peer-driver CAGE.obj OUTDIR [--cells N | --target-vertices V]
//                   [--max-iter N] [--primal-tol E] [--dual-tol E] [--threads T]
//                   [--search-window K] [--mesh-only]
// --cells N is the UI's "Target No. of Cells" spin box (default 3000,
// glwidget.cpp:81). --target-vertices V searches the N whose triangulation has
// the vertex count closest to V (to match Table 2), trying every N within K
// (default 500) of a secant estimate; of equally close ones, the smallest N. --mesh-only stops after
// the triangulation and writes mesh.obj / rig.json only.

#include "LBCSolver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>
#include <fcntl.h>
#include <omp.h>

#ifdef SINGLE
#define REAL float
#else
#define REAL double
#endif
#ifndef VOID
#define VOID void
#endif
#ifndef TRIVOID
#define TRIVOID void
#endif
extern "C" {
#include "external/triangle/triangle.h"
}

extern double lbc_peer_t[5];  // defined in the patched DataSetup.cpp

// Qt-free stand-in for upstream's LBCUI (LBCUI.h): the same data members that
// read_cage / delaunay_Triangulation / domain_area touch, no GL or QImage.
class LBCUI {
public:
    LBCUI()
        : m_edge_length(1.0), m_scale(1.0), m_avg_cage_edge_length(1.0), m_has_cage(false),
          m_has_delaunay(false) {}
    bool read_cage(const std::string &filename);
    void delaunay_Triangulation(int numTriangles);
    double domain_area();

    Eigen::Matrix3Xd m_delaunay, m_delaunay_display;
    Eigen::MatrixXi m_delaunay_faces;
    Eigen::Vector3d m_center;
    Eigen::Matrix3Xd m_cage, m_cage_display;
    Eigen::MatrixXd m_w;
    double m_edge_length;
    double m_scale;
    double m_avg_cage_edge_length;
    bool m_has_cage;
    bool m_has_delaunay;
};

#include "lbcui_extract.inc"

// ---------------------------------------------------------------------------
// small helpers

// Run f with stdout (fd 1, and std::cout) sent to /dev/null: Triangle prints its
// statistics with printf (the UI's switches have no Q) and the UI code prints
// the target area; neither belongs in the benchmark's output.
template <class F> static void quietly(F f) {
    fflush(stdout);
    std::cout.flush();
    int saved = dup(1);
    int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    close(devnull);
    f();
    fflush(stdout);
    std::cout.flush();
    dup2(saved, 1);
    close(saved);
}

static void write_matrix(const std::string &path, const Eigen::MatrixXd &m) {
    FILE *f = fopen(path.c_str(), "w");
    if (!f) { perror(path.c_str()); exit(1); }
    for (int r = 0; r < m.rows(); ++r) {
        for (int c = 0; c < m.cols(); ++c) fprintf(f, c ? " %.17g" : "%.17g", m(r, c));
        fputc('\n', f);
    }
    fclose(f);
}

static std::string fmt(double x) {
    char buf[64];
    snprintf(buf, sizeof buf, "%.17g", x);
    return buf;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        std::cerr << "usage: " << argv[0]
                  << " CAGE.obj OUTDIR [--cells N | --target-vertices V] [--max-iter N]"
                     " [--primal-tol E] [--dual-tol E] [--threads T] [--search-window K] [--mesh-only]\n";
        return 2;
    }
    std::string cage_path = argv[1], outdir = argv[2];
    int cells = 3000;          // glwidget.cpp:81 spinBox_numTriangles_->setValue(3000)
    int target_vertices = -1;
    int search_window = 500;
    bool mesh_only = false;
    int max_iter = 10000;      // glwidget.cpp:40
    double primal_tol = 0.0000001;   // glwidget.cpp:60
    double dual_tol = 0.000001;      // glwidget.cpp:68
    for (int a = 3; a < argc; ++a) {
        std::string s = argv[a];
        if (s == "--cells" && a + 1 < argc) cells = atoi(argv[++a]);
        else if (s == "--target-vertices" && a + 1 < argc) target_vertices = atoi(argv[++a]);
        else if (s == "--max-iter" && a + 1 < argc) max_iter = atoi(argv[++a]);
        else if (s == "--primal-tol" && a + 1 < argc) primal_tol = atof(argv[++a]);
        else if (s == "--dual-tol" && a + 1 < argc) dual_tol = atof(argv[++a]);
        else if (s == "--search-window" && a + 1 < argc) search_window = atoi(argv[++a]);
        else if (s == "--mesh-only") mesh_only = true;
        else if (s == "--threads" && a + 1 < argc) omp_set_num_threads(atoi(argv[++a]));
        else { std::cerr << "unknown argument " << s << "\n"; return 2; }
    }
    // The UI's other solver defaults (glwidget.cpp:37-68, 96-102):
    const int weighting_scheme = 2;           // combobox index 2 "Quadratic" = DataSetup::SQUARE
    const double relaxation_alpha = 1.65;     // glwidget.cpp:46
    const double penalty_weight = 10;         // glwidget.cpp:52

    LBCUI ui;
    if (!ui.read_cage(cage_path)) return 1;
    const int n_cage = ui.m_cage.cols();

    // ---- mesh density: the UI's only knob is "Target No. of Cells".
    auto vertices_for = [&](int n) {
        quietly([&] { ui.delaunay_Triangulation(n); });
        return (int)ui.m_delaunay.cols();
    };
    if (target_vertices > 0) {
        // Secant steps on N, then every N in a window around the estimate;
        // keep the smallest N whose vertex count is closest to the target.
        int n = 3000;
        for (int k = 0; k < 8; ++k) {
            int v = vertices_for(n);
            if (v == target_vertices) break;
            int next = std::max(10, (int)std::lround((double)n * target_vertices / v));
            if (next == n) break;
            n = next;
        }
        int best_n = n, best_d = 1 << 30;
        for (int m = std::max(10, n - search_window); m <= n + search_window; ++m) {
            int d = std::abs(vertices_for(m) - target_vertices);
            if (d < best_d) { best_d = d; best_n = m; }
        }
        cells = best_n;
    }

    // ---- triangulate, exactly as the UI's "Triangulate" button (LBCUI.cpp:160-261)
    double t_tri0 = omp_get_wtime();
    quietly([&] { ui.delaunay_Triangulation(cells); });
    double t_tri1 = omp_get_wtime();

    const int nv = ui.m_delaunay.cols(), nf = ui.m_delaunay_faces.cols();

    // ---- exports that need no solve: the mesh (cage vertices among its
    // vertices, in Triangle's order: the input boundary points first) and a
    // c2warp rig with the same cage in the file's order
    {
        std::ofstream obj(outdir + "/mesh.obj");
        obj << "# " << cage_path << " triangulated as LBCUI::delaunay_Triangulation(" << cells
            << ") does (Triangle switches pza<area>q33.0Y)\n";
        for (int i = 0; i < nv; ++i)
            obj << "v " << fmt(ui.m_delaunay(0, i)) << " " << fmt(ui.m_delaunay(1, i)) << " 0\n";
        for (int f = 0; f < nf; ++f)
            obj << "f " << ui.m_delaunay_faces(0, f) + 1 << " " << ui.m_delaunay_faces(1, f) + 1 << " "
                << ui.m_delaunay_faces(2, f) + 1 << "\n";
    }
    {
        std::ofstream rig(outdir + "/rig.json");
        rig << "{\n  \"version\": 1,\n  \"method\": \"lbc\",\n  \"handles\": [],\n  \"cage\": {\"rest\": [";
        for (int i = 0; i < n_cage; ++i)
            rig << (i ? ", " : "") << "[" << fmt(ui.m_cage(0, i)) << ", " << fmt(ui.m_cage(1, i)) << "]";
        rig << "]},\n  \"lbc\": {\"tau\": \"square\"}\n}\n";
    }
    if (mesh_only) {
        printf("cells parameter  %d\nmesh vertices    %d\ntriangles        %d\ncage vertices    %d\n", cells, nv, nf,
               n_cage);
        return 0;
    }

    // ---- "Compute LBC": LBCUI::lbc_solver (LBCUI.cpp:280-368), stages timed
    double t0 = omp_get_wtime();
    LBC::DenseMatrix sample_points = ui.m_delaunay.block(0, 0, 2, ui.m_delaunay.cols());
    LBC::DenseIndexMatrix &cell_vertices = ui.m_delaunay_faces;

    LBC::IndexVector control_point_idx(ui.m_cage.cols());
    for (int i = 0; i < ui.m_cage.cols(); ++i) {
        Eigen::Vector2d ctrl_pt = ui.m_cage.block(0, i, 2, 1);
        LBC::DenseMatrix candidate_points = sample_points;
        int min_idx = -1;
        (candidate_points.colwise() - ctrl_pt).colwise().norm().minCoeff(&min_idx);
        control_point_idx[i] = min_idx;
    }

    std::vector<LBC::DataSetup::CageBoundaryFacetInfo> boundary_facet_info;
    int n_control_pt = ui.m_cage.cols();
    for (int i = 0; i < n_control_pt; ++i) {
        int next_i = (i + 1) % n_control_pt;
        LBC::IndexVector facet_vertices(2);
        facet_vertices(0) = i;
        facet_vertices(1) = next_i;
        int n_segments = std::ceil((ui.m_cage.col(i) - ui.m_cage.col(next_i)).norm() / ui.m_edge_length);
        LBC::IndexVector boundary_points(n_segments - 1);
        for (int k = 1; k < n_segments; ++k) {
            Eigen::Vector3d pt_3d = ui.m_cage.col(i) + k * (ui.m_cage.col(next_i) - ui.m_cage.col(i)) / n_segments;
            Eigen::Vector2d pt = pt_3d.head(2);
            LBC::DenseMatrix candidate_points = sample_points;
            int min_idx = -1;
            (candidate_points.colwise() - pt).colwise().norm().minCoeff(&min_idx);
            boundary_points[k - 1] = min_idx;
        }
        LBC::DataSetup::CageBoundaryFacetInfo edge(facet_vertices, boundary_points);
        boundary_facet_info.push_back(edge);
    }
    double t1 = omp_get_wtime();

    LBC::DataSetup::WeightingScheme scheme = static_cast<LBC::DataSetup::WeightingScheme>(weighting_scheme);
    LBC::DataSetup ds(sample_points, control_point_idx, cell_vertices, boundary_facet_info, scheme);
    double t2 = omp_get_wtime();

    LBC::Param param;
    param.max_iterations = max_iter;
    param.relaxation_alpha = relaxation_alpha;
    param.convergence_check_frequency = 10;
    param.output_frequency_ratio = 10;
    param.rel_primal_eps = primal_tol;
    param.rel_dual_eps = dual_tol;
    param.penalty_weight = penalty_weight;
    LBC::LBCSolver solver(param, ds);   // factorises G^T G + I, SVD of the constraints
    double t3 = omp_get_wtime();

    // solve() prints its progress on std::cout; keep it, to read the final
    // iteration count, and pass it on to stderr.
    std::ostringstream solver_log;
    std::streambuf *old_buf = std::cout.rdbuf(solver_log.rdbuf());
    solver.solve();
    std::cout.rdbuf(old_buf);
    double t4 = omp_get_wtime();
    std::cerr << solver_log.str();

    LBC::DenseMatrix W = ds.get_full_coordinate_values(solver.get_coordinates());  // LBCUI.cpp:366

    int iterations = -1;
    bool converged = solver_log.str().find("Solver converged.") != std::string::npos;
    {
        std::istringstream in(solver_log.str());
        std::string line;
        while (std::getline(in, line))
            if (line.rfind("Iteration ", 0) == 0) iterations = atoi(line.c_str() + 10);
    }

    // Objective as their code defines it: the ADMM's X is the integrated gradient
    // G Z + E (area times gradient, in DataSetup's frame: centroid at 0, farthest
    // sample at 250), the shrinkage weights are grad_weights (phi per cell).
    const LBC::SparseMatrix &G = ds.get_LBC_solver_grad_operator();
    const LBC::DenseMatrix &E = ds.get_LBC_solver_grad_const();
    const LBC::DenseMatrix &phi = ds.get_LBC_solver_grad_weights();
    LBC::DenseMatrix grad = G * solver.get_coordinates() + E;
    double objective = 0.0;
    for (int i = 0; i < phi.cols(); ++i)
        for (int f = 0; f < phi.rows(); ++f)
            objective += phi(f, i) * grad.block(2 * f, i, 2, 1).norm();

    // DataSetup's stage timestamps (patched in): setup, geodesics, phi
    double ds_setup = lbc_peer_t[1] - lbc_peer_t[0];
    double geo_factor = lbc_peer_t[2] - lbc_peer_t[1];
    double geo_solve = lbc_peer_t[3] - lbc_peer_t[2];
    double ds_phi = lbc_peer_t[4] - lbc_peer_t[3];
    (void)ds_setup; (void)ds_phi;
    double geodesics = geo_factor + geo_solve;
    // setup: the UI's nearest-vertex searches + everything in DataSetup but the
    // geodesic step (normalising, boundary values, operators, phi)
    double setup = (t2 - t0) - geodesics;
    double factorisation = t3 - t2;
    double iters_time = t4 - t3;
    double total = t4 - t0;

    // ---- exports of the result
    write_matrix(outdir + "/their_weights.txt", W);
    write_matrix(outdir + "/their_geodesics.txt", ds.get_geodesic_distance());
    {
        std::ofstream idx(outdir + "/cage_vertex_index.txt");
        for (int i = 0; i < n_cage; ++i) idx << control_point_idx[i] << "\n";
    }
    {
        std::ofstream js(outdir + "/their_stats.json");
        js << std::setprecision(17) << "{\"cage\": \"" << cage_path << "\", \"cells_param\": " << cells
           << ", \"edge_length\": " << ui.m_edge_length << ", \"vertices\": " << nv << ", \"triangles\": " << nf
           << ", \"cage_vertices\": " << n_cage << ", \"threads\": " << omp_get_max_threads()
           << ", \"triangulate_s\": " << (t_tri1 - t_tri0) << ", \"setup_s\": " << setup
           << ", \"geodesics_s\": " << geodesics << ", \"geodesic_factor_s\": " << geo_factor
           << ", \"geodesic_solve_s\": " << geo_solve << ", \"factorisation_s\": " << factorisation
           << ", \"iterations_s\": " << iters_time << ", \"total_s\": " << total
           << ", \"iterations\": " << iterations << ", \"converged\": " << (converged ? "true" : "false")
           << ", \"objective\": " << objective << ", \"min_weight\": " << W.minCoeff()
           << ", \"max_weight\": " << W.maxCoeff() << "}\n";
    }

    printf("model            %s\n", cage_path.c_str());
    printf("cells parameter  %d (edge length %.6g)\n", cells, ui.m_edge_length);
    printf("mesh vertices    %d\n", nv);
    printf("triangles        %d\n", nf);
    printf("cage vertices    %d\n", n_cage);
    printf("threads          %d\n", omp_get_max_threads());
    printf("triangulate      %.3f s (not in total)\n", t_tri1 - t_tri0);
    printf("setup            %.3f s\n", setup);
    printf("geodesics        %.3f s (factorisations %.3f, solves %.3f)\n", geodesics, geo_factor, geo_solve);
    printf("factorisation    %.3f s\n", factorisation);
    printf("iterations       %.3f s\n", iters_time);
    printf("total            %.3f s\n", total);
    printf("iteration count  %d (%s)\n", iterations, converged ? "converged" : "max iterations reached");
    printf("objective        %.10g (their frame, their phi)\n", objective);
    printf("weights min/max  %.3g / %.6g\n", W.minCoeff(), W.maxCoeff());
    return 0;
}
