//! The detector's small convolutional networks run directly, without OpenCV's dnn module, on
//! CPUs with AVX2 and FMA (`detect.default.builtin_nets`).
//!
//! `scripts/train-hubnet.py` writes every network as a chain of `Conv` nodes (any kernel,
//! stride, symmetric padding and dilation, one group), each but the last followed by `Relu`.
//! On those shapes (8–96 channels, 1–96 px sides) OpenCV 4.6's dnn module reaches about a
//! quarter of the FMA units' throughput; here each layer is a direct convolution over a
//! zero-padded channels-last image, in register tiles of 6 or 12 output pixels × 16 or 8
//! output channels, the input broadcast and the weights loaded once per tile (the hub heatmap
//! network takes ~0.4 ms a frame here against ~0.9 ms in the dnn module). The sums run in another order than OpenCV's, so
//! outputs differ from the dnn module's by float rounding (~1e-5 of the logits; tested).
//! Elsewhere (other CPUs, other layer types) [`ConvNet::from_onnx`] gives `None` and the dnn
//! module runs the model.

use crate::DetectError;

/// One convolution layer, its weights packed for the kernel in use.
#[derive(Debug, Clone)]
struct Layer {
    in_ch: usize,
    out_ch: usize,
    kernel: usize,
    stride: usize,
    pad: usize,
    dilation: usize,
    relu: bool,
    /// Weights `[ky][kx][in][out]`, for the plain loop (output channels not a multiple of 8).
    plain: Vec<f32>,
    bias: Vec<f32>,
    /// Output channels per tile block: 16, 8, or 0 (the plain loop).
    block: usize,
    /// Per block of output channels: weights `[ky][kx][in][block]`.
    packed: Vec<Vec<f32>>,
}

impl Layer {
    /// Output size for an input of `h`×`w`; `None` when the input is too small.
    fn out_size(&self, h: usize, w: usize) -> Option<(usize, usize)> {
        let reach = self.dilation * (self.kernel - 1) + 1;
        let (ph, pw) = (h + 2 * self.pad, w + 2 * self.pad);
        (ph >= reach && pw >= reach).then(|| {
            (
                (ph - reach) / self.stride + 1,
                (pw - reach) / self.stride + 1,
            )
        })
    }
}

/// A chain of convolutions with ReLU between them, run on the CPU's vector units.
#[derive(Debug, Clone)]
pub struct ConvNet {
    layers: Vec<Layer>,
    /// Zero-padded input of the layer being run, channels last.
    padded: Vec<f32>,
    /// Layer outputs, channels last (ping-pong).
    bufs: [Vec<f32>; 2],
}

impl ConvNet {
    /// The network in the ONNX model `model`, or `None` when this CPU lacks AVX2 and FMA or the
    /// model holds other layers than a chain of `Conv` (+ `Relu`). An error when the model
    /// cannot be read.
    pub fn from_onnx(model: &[u8]) -> Result<Option<ConvNet>, DetectError> {
        if !vector_units() {
            return Ok(None);
        }
        let Some(specs) = onnx::conv_chain(model).map_err(DetectError::Model)? else {
            return Ok(None);
        };
        let layers = specs.into_iter().map(pack).collect();
        Ok(Some(ConvNet {
            layers,
            padded: Vec::new(),
            bufs: [Vec::new(), Vec::new()],
        }))
    }

    /// Runs the network on one grey image of `h`×`w` 8-bit pixels (row-major, scaled to
    /// [0, 1] as the networks were trained) and returns the last layer's output, channels
    /// last (for one output channel: row-major). An error when the image is too small for
    /// the layers.
    pub fn run(&mut self, pixels: &[u8], h: usize, w: usize) -> Result<&[f32], DetectError> {
        if pixels.len() != h * w || self.layers.first().is_some_and(|l| l.in_ch != 1) {
            return Err(DetectError::Model(format!(
                "network input of {} bytes is not one {w}x{h} grey image",
                pixels.len()
            )));
        }
        let [mut cur, mut next] = std::mem::take(&mut self.bufs);
        cur.clear();
        cur.extend(pixels.iter().map(|&p| f32::from(p) * (1.0 / 255.0)));
        let (mut h, mut w) = (h, w);
        for l in &self.layers {
            let (oh, ow) = l.out_size(h, w).ok_or_else(|| {
                DetectError::Model(format!(
                    "a {w}x{h} input is too small for a {}x{} kernel",
                    l.kernel, l.kernel
                ))
            })?;
            pad_input(&cur, h, w, l, &mut self.padded);
            next.clear();
            next.resize(oh * ow * l.out_ch, 0.0);
            conv(l, &self.padded, w + 2 * l.pad, (oh, ow), &mut next);
            std::mem::swap(&mut cur, &mut next);
            (h, w) = (oh, ow);
        }
        self.bufs = [cur, next];
        Ok(&self.bufs[0])
    }
}

/// The CPU has the vector units the kernel is written for.
fn vector_units() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Packs a layer's ONNX weights (`[out][in][ky][kx]`) for the kernel.
fn pack(s: onnx::ConvSpec) -> Layer {
    let (o, i, k) = (s.out_ch, s.in_ch, s.kernel);
    let at =
        |oc: usize, ic: usize, ky: usize, kx: usize| s.weights[((oc * i + ic) * k + ky) * k + kx];
    let block = if o % 16 == 0 {
        16
    } else if o % 8 == 0 {
        8
    } else {
        0
    };
    let mut plain = Vec::with_capacity(o * i * k * k);
    for ky in 0..k {
        for kx in 0..k {
            for ic in 0..i {
                plain.extend((0..o).map(|oc| at(oc, ic, ky, kx)));
            }
        }
    }
    // Block 0 (the plain loop) packs nothing.
    let packed = match o.checked_div(block) {
        None => Vec::new(),
        Some(blocks) => (0..blocks)
            .map(|b| {
                let mut w = Vec::with_capacity(block * i * k * k);
                for ky in 0..k {
                    for kx in 0..k {
                        for ic in 0..i {
                            w.extend((0..block).map(|j| at(b * block + j, ic, ky, kx)));
                        }
                    }
                }
                w
            })
            .collect(),
    };
    Layer {
        in_ch: i,
        out_ch: o,
        kernel: k,
        stride: s.stride,
        pad: s.pad,
        dilation: s.dilation,
        relu: s.relu,
        plain,
        bias: s.bias,
        block,
        packed,
    }
}

/// Copies the `h`×`w` channels-last `input` into the middle of a zero border of `l.pad` px.
fn pad_input(input: &[f32], h: usize, w: usize, l: &Layer, padded: &mut Vec<f32>) {
    let (pw, c, p) = (w + 2 * l.pad, l.in_ch, l.pad);
    padded.clear();
    padded.resize((h + 2 * p) * pw * c, 0.0);
    for y in 0..h {
        padded[((y + p) * pw + p) * c..][..w * c].copy_from_slice(&input[y * w * c..][..w * c]);
    }
}

/// One layer over the padded input (`pw` px a row) into `out` (`oh`×`ow`×`out_ch`).
fn conv(l: &Layer, padded: &[f32], pw: usize, (oh, ow): (usize, usize), out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if l.block > 0 {
        // SAFETY: layers are only built when the CPU has AVX2 and FMA (`vector_units`); the
        // tiles read inside `padded` (sized from the same layer geometry) and write inside `out`.
        unsafe { x86::conv_tiles(l, padded, pw, (oh, ow), out) };
        return;
    }
    conv_plain(l, padded, pw, (oh, ow), out);
}

/// The plain loop: few output channels (the 1×1 layers that make the logits).
fn conv_plain(l: &Layer, padded: &[f32], pw: usize, (oh, ow): (usize, usize), out: &mut [f32]) {
    let (ic, oc, k) = (l.in_ch, l.out_ch, l.kernel);
    for oy in 0..oh {
        for ox in 0..ow {
            let dst = &mut out[(oy * ow + ox) * oc..][..oc];
            dst.copy_from_slice(&l.bias);
            for ky in 0..k {
                for kx in 0..k {
                    let src = &padded[((oy * l.stride + ky * l.dilation) * pw
                        + ox * l.stride
                        + kx * l.dilation)
                        * ic..][..ic];
                    let wk = &l.plain[(ky * k + kx) * ic * oc..][..ic * oc];
                    for (a, wr) in src.iter().zip(wk.chunks_exact(oc)) {
                        for (d, wv) in dst.iter_mut().zip(wr) {
                            *d += a * wv;
                        }
                    }
                }
            }
            if l.relu {
                dst.iter_mut().for_each(|d| *d = d.max(0.0));
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Layer;
    use std::arch::x86_64::*;

    /// All tiles of one layer.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn conv_tiles(
        l: &Layer,
        padded: &[f32],
        pw: usize,
        (oh, ow): (usize, usize),
        out: &mut [f32],
    ) {
        for (b, weights) in l.packed.iter().enumerate() {
            let oc0 = b * l.block;
            let bias = &l.bias[oc0..oc0 + l.block];
            match l.block {
                16 => row_tiles::<2, 6>(l, padded, pw, (oh, ow), weights, bias, oc0, out),
                _ => row_tiles::<1, 12>(l, padded, pw, (oh, ow), weights, bias, oc0, out),
            }
        }
    }

    /// Tiles of `P` pixels × `M`·8 channels along every output row; a row's last tile
    /// overlaps the one before when `P` does not divide it (recomputing pixels is cheaper
    /// than narrow tiles); rows narrower than a tile go a pixel at a time.
    #[inline(always)]
    // The AVX2 kernel's loop state, passed loose so that every piece stays in a register once
    // inlined into the `target_feature` function; a struct would gain nothing here.
    #[allow(clippy::too_many_arguments)]
    unsafe fn row_tiles<const M: usize, const P: usize>(
        l: &Layer,
        padded: &[f32],
        pw: usize,
        (oh, ow): (usize, usize),
        weights: &[f32],
        bias: &[f32],
        oc0: usize,
        out: &mut [f32],
    ) {
        for oy in 0..oh {
            if ow < P {
                for ox in 0..ow {
                    tile::<M, 1>(l, padded, pw, weights, bias, (oy, ox), ow, oc0, out);
                }
                continue;
            }
            let mut ox = 0;
            while ox + P <= ow {
                tile::<M, P>(l, padded, pw, weights, bias, (oy, ox), ow, oc0, out);
                ox += P;
            }
            if ox < ow {
                tile::<M, P>(l, padded, pw, weights, bias, (oy, ow - P), ow, oc0, out);
            }
        }
    }

    /// Output pixels `ox .. ox + P` of row `oy`, channels `oc0 .. oc0 + 8·M`.
    #[inline(always)]
    // As `row_tiles`: the innermost AVX2 kernel, its arguments kept in registers.
    #[allow(clippy::too_many_arguments)]
    unsafe fn tile<const M: usize, const P: usize>(
        l: &Layer,
        padded: &[f32],
        pw: usize,
        weights: &[f32],
        bias: &[f32],
        (oy, ox): (usize, usize),
        ow: usize,
        oc0: usize,
        out: &mut [f32],
    ) {
        let ic = l.in_ch;
        let step = l.stride * ic;
        let mut acc = [[_mm256_setzero_ps(); M]; P];
        for row in acc.iter_mut() {
            for (m, a) in row.iter_mut().enumerate() {
                *a = _mm256_loadu_ps(bias.as_ptr().add(8 * m));
            }
        }
        for ky in 0..l.kernel {
            let iy = oy * l.stride + ky * l.dilation;
            for kx in 0..l.kernel {
                let wk = weights.as_ptr().add((ky * l.kernel + kx) * ic * 8 * M);
                let src = padded
                    .as_ptr()
                    .add((iy * pw + ox * l.stride + kx * l.dilation) * ic);
                for i in 0..ic {
                    let mut w = [_mm256_setzero_ps(); M];
                    for (m, wv) in w.iter_mut().enumerate() {
                        *wv = _mm256_loadu_ps(wk.add((i * M + m) * 8));
                    }
                    for (j, row) in acc.iter_mut().enumerate() {
                        let a = _mm256_broadcast_ss(&*src.add(j * step + i));
                        for (av, wv) in row.iter_mut().zip(&w) {
                            *av = _mm256_fmadd_ps(*wv, a, *av);
                        }
                    }
                }
            }
        }
        let zero = _mm256_setzero_ps();
        for (j, row) in acc.iter().enumerate() {
            let dst = out.as_mut_ptr().add((oy * ow + ox + j) * l.out_ch + oc0);
            for (m, a) in row.iter().enumerate() {
                let v = if l.relu { _mm256_max_ps(*a, zero) } else { *a };
                _mm256_storeu_ps(dst.add(8 * m), v);
            }
        }
    }
}

/// The few parts of ONNX's protobuf format the networks use.
mod onnx {
    /// One `Conv` node (and whether a `Relu` follows it).
    #[derive(Debug, Clone)]
    pub(super) struct ConvSpec {
        pub in_ch: usize,
        pub out_ch: usize,
        pub kernel: usize,
        pub stride: usize,
        pub pad: usize,
        pub dilation: usize,
        pub relu: bool,
        /// `[out][in][ky][kx]`.
        pub weights: Vec<f32>,
        pub bias: Vec<f32>,
    }

    /// A protobuf field: number and value.
    enum Value<'a> {
        Int(u64),
        Bytes(&'a [u8]),
        Fixed32(u32),
        Fixed64,
    }

    /// The fields of one protobuf message.
    fn fields(mut b: &[u8]) -> Result<Vec<(u32, Value<'_>)>, String> {
        let mut out = Vec::new();
        while !b.is_empty() {
            let key = varint(&mut b)?;
            let (num, wire) = ((key >> 3) as u32, key & 7);
            let v = match wire {
                0 => Value::Int(varint(&mut b)?),
                1 => {
                    b = b.get(8..).ok_or("truncated fixed64")?;
                    Value::Fixed64
                }
                2 => {
                    let n = varint(&mut b)? as usize;
                    let (v, rest) = (b.get(..n).ok_or("truncated field")?, &b[n..]);
                    b = rest;
                    Value::Bytes(v)
                }
                5 => {
                    let v = b.get(..4).ok_or("truncated fixed32")?;
                    b = &b[4..];
                    Value::Fixed32(u32::from_le_bytes([v[0], v[1], v[2], v[3]]))
                }
                w => return Err(format!("unknown protobuf wire type {w}")),
            };
            out.push((num, v));
        }
        Ok(out)
    }

    fn varint(b: &mut &[u8]) -> Result<u64, String> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let (&byte, rest) = b.split_first().ok_or("truncated varint")?;
            *b = rest;
            v |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err("varint too long".into())
    }

    fn string(v: &Value<'_>) -> String {
        match v {
            Value::Bytes(b) => String::from_utf8_lossy(b).into_owned(),
            _ => String::new(),
        }
    }

    /// Repeated int64 (packed or not) into `out`.
    fn ints(v: &Value<'_>, out: &mut Vec<i64>) -> Result<(), String> {
        match v {
            Value::Int(i) => out.push(*i as i64),
            Value::Bytes(mut b) => {
                while !b.is_empty() {
                    out.push(varint(&mut b)? as i64);
                }
            }
            _ => return Err("bad int field".into()),
        }
        Ok(())
    }

    /// A float tensor: name, dims, values.
    struct Tensor {
        name: String,
        dims: Vec<i64>,
        values: Vec<f32>,
    }

    fn tensor(b: &[u8]) -> Result<Tensor, String> {
        let mut t = Tensor {
            name: String::new(),
            dims: Vec::new(),
            values: Vec::new(),
        };
        let mut data_type = 1;
        for (num, v) in fields(b)? {
            match num {
                1 => ints(&v, &mut t.dims)?,
                2 => {
                    if let Value::Int(d) = v {
                        data_type = d;
                    }
                }
                4 => match v {
                    Value::Bytes(raw) => t.values.extend(
                        raw.chunks_exact(4)
                            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
                    ),
                    Value::Fixed32(x) => t.values.push(f32::from_bits(x)),
                    _ => return Err("bad float_data".into()),
                },
                8 => t.name = string(&v),
                9 => {
                    if let Value::Bytes(raw) = v {
                        t.values = raw
                            .chunks_exact(4)
                            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                            .collect();
                    }
                }
                _ => {}
            }
        }
        if data_type != 1 {
            return Err(format!("tensor {} is not float (type {data_type})", t.name));
        }
        Ok(t)
    }

    /// A graph node: operator, inputs, outputs, integer attributes.
    struct Node {
        op: String,
        inputs: Vec<String>,
        outputs: Vec<String>,
        attrs: Vec<(String, Vec<i64>)>,
    }

    fn node(b: &[u8]) -> Result<Node, String> {
        let mut n = Node {
            op: String::new(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            attrs: Vec::new(),
        };
        for (num, v) in fields(b)? {
            match num {
                1 => n.inputs.push(string(&v)),
                2 => n.outputs.push(string(&v)),
                4 => n.op = string(&v),
                5 => {
                    let Value::Bytes(a) = v else { continue };
                    let (mut name, mut values) = (String::new(), Vec::new());
                    for (anum, av) in fields(a)? {
                        match anum {
                            1 => name = string(&av),
                            3 | 8 => ints(&av, &mut values)?,
                            _ => {}
                        }
                    }
                    n.attrs.push((name, values));
                }
                _ => {}
            }
        }
        Ok(n)
    }

    /// The model's chain of `Conv` (+ `Relu`) layers; `None` when it holds anything else.
    pub(super) fn conv_chain(model: &[u8]) -> Result<Option<Vec<ConvSpec>>, String> {
        let graph = fields(model)?
            .into_iter()
            .find_map(|(num, v)| match (num, v) {
                (7, Value::Bytes(g)) => Some(g),
                _ => None,
            })
            .ok_or("no graph in the model")?;
        let (mut nodes, mut tensors) = (Vec::new(), Vec::new());
        for (num, v) in fields(graph)? {
            match (num, v) {
                (1, Value::Bytes(b)) => nodes.push(node(b)?),
                (5, Value::Bytes(b)) => tensors.push(tensor(b)?),
                _ => {}
            }
        }
        let find = |name: &str| tensors.iter().find(|t| t.name == name);
        let mut specs: Vec<ConvSpec> = Vec::new();
        let mut last_output = None::<String>;
        for n in &nodes {
            // Each node reads the one before it.
            if let Some(prev) = &last_output {
                if n.inputs.first() != Some(prev) {
                    return Ok(None);
                }
            }
            match n.op.as_str() {
                "Relu" if specs.last().is_some_and(|s| !s.relu) => {
                    specs.last_mut().unwrap().relu = true
                }
                "Conv" => {
                    let (Some(w), Some(b)) = (
                        n.inputs.get(1).and_then(|i| find(i)),
                        n.inputs.get(2).and_then(|i| find(i)),
                    ) else {
                        return Ok(None);
                    };
                    let attr = |name: &str| {
                        n.attrs
                            .iter()
                            .find(|(a, _)| a == name)
                            .map(|(_, v)| v.clone())
                    };
                    let square = |v: Option<Vec<i64>>, default: i64| -> Option<usize> {
                        let v = v.unwrap_or_else(|| vec![default]);
                        (v.iter().all(|x| *x == v[0]) && v[0] >= 0).then_some(v[0] as usize)
                    };
                    let (Some(stride), Some(pad), Some(dilation), Some(group)) = (
                        square(attr("strides"), 1),
                        square(attr("pads"), 0),
                        square(attr("dilations"), 1),
                        square(attr("group"), 1),
                    ) else {
                        return Ok(None);
                    };
                    let [o, i, kh, kw] = w.dims[..] else {
                        return Ok(None);
                    };
                    if group != 1
                        || kh != kw
                        || kh < 1
                        || stride < 1
                        || dilation < 1
                        || b.values.len() != o as usize
                        || w.values.len() != (o * i * kh * kw) as usize
                    {
                        return Ok(None);
                    }
                    if specs.last().is_some_and(|s| s.out_ch != i as usize) {
                        return Ok(None);
                    }
                    specs.push(ConvSpec {
                        in_ch: i as usize,
                        out_ch: o as usize,
                        kernel: kh as usize,
                        stride,
                        pad,
                        dilation,
                        relu: false,
                        weights: w.values.clone(),
                        bias: b.values.clone(),
                    });
                }
                _ => return Ok(None),
            }
            last_output = n.outputs.first().cloned();
        }
        Ok((!specs.is_empty()).then_some(specs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::heat;
    use opencv::core::{Mat, Scalar, Size, Vector};
    use opencv::dnn;
    use opencv::prelude::*;

    /// The shipped models give the dnn module's outputs to float rounding.
    #[test]
    fn the_shipped_networks_match_opencv_dnn() {
        let models: [(&str, &[u8], usize, usize); 7] = [
            ("hubnet", include_bytes!("../models/hubnet.onnx"), 128, 192),
            (
                "hubnet-still",
                include_bytes!("../models/hubnet-still.onnx"),
                128,
                192,
            ),
            ("hubcrop", include_bytes!("../models/hubcrop.onnx"), 64, 64),
            (
                "hubcrop-still",
                include_bytes!("../models/hubcrop-still.onnx"),
                64,
                64,
            ),
            ("hubyaw", include_bytes!("../models/hubyaw.onnx"), 64, 64),
            (
                "hubyaw-thesis",
                include_bytes!("../models/hubyaw-thesis.onnx"),
                64,
                64,
            ),
            (
                "hubyaw-close",
                include_bytes!("../models/hubyaw-close.onnx"),
                64,
                64,
            ),
        ];
        let Some(_) = ConvNet::from_onnx(models[0].1).unwrap() else {
            eprintln!("skipped: this CPU lacks AVX2/FMA, the dnn module runs the networks");
            return;
        };
        for (name, model, h, w) in models {
            let mut net = ConvNet::from_onnx(model)
                .unwrap()
                .unwrap_or_else(|| panic!("{name}: not a Conv/Relu chain"));
            // A smooth pattern with texture, as a frame would be.
            let pixels: Vec<u8> = (0..h * w)
                .map(|k| ((k % w) * 3 + (k / w) * 5 + ((k * 2654435761) >> 20) % 40) as u8)
                .collect();
            let ours = net.run(&pixels, h, w).unwrap().to_vec();
            let img = Mat::new_rows_cols_with_data::<u8>(h as i32, w as i32, &pixels)
                .unwrap()
                .try_clone()
                .unwrap();
            let blob = dnn::blob_from_image(
                &img,
                1.0 / 255.0,
                Size::new(w as i32, h as i32),
                Scalar::default(),
                false,
                false,
                opencv::core::CV_32F,
            )
            .unwrap();
            let mut cv = dnn::read_net_from_onnx_buffer(&Vector::<u8>::from_slice(model)).unwrap();
            cv.set_input(&blob, "", 1.0, Scalar::default()).unwrap();
            let out = cv.forward_single("").unwrap();
            let theirs = out.data_typed::<f32>().unwrap();
            assert_eq!(ours.len(), theirs.len(), "{name}");
            let scale = theirs.iter().fold(1.0f32, |m, v| m.max(v.abs()));
            let worst = ours
                .iter()
                .zip(theirs)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst <= 1e-4 * scale,
                "{name}: largest difference {worst} (logits up to {scale})"
            );
        }
    }

    #[test]
    fn bad_models_and_inputs_are_errors() {
        assert!(ConvNet::from_onnx(b"\x3a\xff").is_err() || !vector_units());
        let Some(mut net) = ConvNet::from_onnx(include_bytes!("../models/hubyaw.onnx")).unwrap()
        else {
            return;
        };
        // The wrong number of pixels; an image smaller than the yaw network's 8×8 kernel needs.
        assert!(matches!(
            net.run(&[0u8; 10], 4, 4),
            Err(DetectError::Model(_))
        ));
        assert!(matches!(
            net.run(&[0u8; 16], 4, 4),
            Err(DetectError::Model(_))
        ));
        assert_eq!(
            net.run(&[0u8; 64 * 64], 64, 64).unwrap().len(),
            heat::YAW_BINS
        );
    }
}
